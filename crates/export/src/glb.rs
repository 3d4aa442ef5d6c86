//! The animated glTF 2.0 binary (`sequence.glb`): the face mesh with UVs, normals and the fused
//! texture, its morph targets (named ARKit shapes first, then the residual components, names in
//! `mesh.extras.targetNames`), one animation with the targets' `weights` and the head's
//! translation and rotation per key frame, and the video's camera at the origin.
//!
//! Coordinates: glTF's (metres, y up, the camera looking down −z, the face towards +z); the
//! camera node at the origin sees the face where the video did (its principal point is taken
//! at the image centre — glTF cameras have no other).

use gltf_json as json;
use json::validation::{Checked, USize64};
use json::Index;
use serde_json::value::RawValue;
use visage_camera::vec3::norm;
use visage_camera::Intrinsics;
use visage_render::normals::vertex_normal_sums;

use crate::morph_animation::MorphAnimation;
use crate::ExportError;

/// Builds the glb: `texture_png` (an encoded PNG) becomes the base colour when given.
///
/// # Errors
/// The JSON cannot be serialised (not expected).
pub fn write_glb(
    animation: &MorphAnimation,
    triangles: &[[u32; 3]],
    uvs: &[[f64; 2]],
    intrinsics: &Intrinsics,
    texture_png: Option<&[u8]>,
    extras: serde_json::Value,
) -> Result<Vec<u8>, ExportError> {
    let mut b = Builder::default();
    let n = animation.base.len();

    let positions = b.vec3(&animation.base, Some(json::buffer::Target::ArrayBuffer));
    let normals = b.vec3(
        &vertex_normals(&animation.base, triangles),
        Some(json::buffer::Target::ArrayBuffer),
    );
    let mut attributes = std::collections::BTreeMap::new();
    attributes.insert(Checked::Valid(json::mesh::Semantic::Positions), positions);
    attributes.insert(Checked::Valid(json::mesh::Semantic::Normals), normals);
    if uvs.len() == n {
        // glTF's v runs down the image, OBJ's (and the mesh's) up.
        let uv: Vec<f32> = uvs
            .iter()
            .flat_map(|t| [t[0] as f32, 1.0 - t[1] as f32])
            .collect();
        let view = b.view(bytes_of(&uv), Some(json::buffer::Target::ArrayBuffer));
        let a = b.accessor(view, n, json::accessor::Type::Vec2, None);
        attributes.insert(Checked::Valid(json::mesh::Semantic::TexCoords(0)), a);
    }
    let flat: Vec<u32> = triangles.iter().flatten().copied().collect();
    let index_view = b.view(
        bytes_of_u32(&flat),
        Some(json::buffer::Target::ElementArrayBuffer),
    );
    let indices = b.accessor_of(
        index_view,
        flat.len(),
        json::accessor::Type::Scalar,
        json::accessor::ComponentType::U32,
        None,
    );
    let targets: Vec<json::mesh::MorphTarget> = animation
        .targets
        .iter()
        .map(|t| json::mesh::MorphTarget {
            // Vertex data like the base positions: a viewer may upload it as an array buffer.
            positions: Some(b.vec3(t, Some(json::buffer::Target::ArrayBuffer))),
            normals: None,
            tangents: None,
        })
        .collect();

    let material = b.material(texture_png);
    let target_names = serde_json::json!({ "targetNames": animation.names });
    let mesh = b.root.push(json::Mesh {
        extensions: None,
        extras: raw(&target_names)?,
        name: Some("face".into()),
        primitives: vec![json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: None,
            indices: Some(indices),
            material: Some(material),
            mode: Checked::Valid(json::mesh::Mode::Triangles),
            targets: (!targets.is_empty()).then_some(targets),
        }],
        weights: (!animation.targets.is_empty()).then(|| vec![0.0; animation.targets.len()]),
    });
    let face = b.root.push(json::Node {
        mesh: Some(mesh),
        name: Some("face".into()),
        rotation: animation
            .rotations
            .first()
            .map(|q| json::scene::UnitQuaternion(*q)),
        translation: animation.translations.first().copied(),
        ..Default::default()
    });
    let camera = b.root.push(json::Camera {
        name: Some("video camera".into()),
        orthographic: None,
        perspective: Some(json::camera::Perspective {
            aspect_ratio: Some(intrinsics.width as f32 / intrinsics.height as f32),
            yfov: (2.0 * (0.5 * intrinsics.height as f64 / intrinsics.fy).atan()) as f32,
            zfar: Some(100.0),
            znear: 0.01,
            extensions: None,
            extras: None,
        }),
        type_: Checked::Valid(json::camera::Type::Perspective),
        extensions: None,
        extras: None,
    });
    let camera_node = b.root.push(json::Node {
        camera: Some(camera),
        name: Some("video camera".into()),
        ..Default::default()
    });
    b.animation(animation, face);
    let scene = b.root.push(json::Scene {
        extensions: None,
        extras: None,
        name: Some("capture".into()),
        nodes: vec![face, camera_node],
    });
    b.root.scene = Some(scene);
    b.root.asset = json::Asset {
        generator: Some(format!("visage {}", env!("CARGO_PKG_VERSION"))),
        extras: raw(&extras)?,
        ..Default::default()
    };
    b.finish()
}

/// Unit area-weighted vertex normals in `f32` ([`visage_render::normals::vertex_normal_sums`]
/// divided by their norm in `f64`, then rounded), `+z` for a vertex of no or only degenerate
/// triangles (glTF requires unit normals).
fn vertex_normals(vertices: &[[f32; 3]], triangles: &[[u32; 3]]) -> Vec<[f32; 3]> {
    let vertices: Vec<[f64; 3]> = vertices.iter().map(|p| p.map(f64::from)).collect();
    vertex_normal_sums(&vertices, triangles)
        .iter()
        .map(|&n| {
            let len = norm(n);
            if len > 0.0 {
                n.map(|x| (x / len) as f32)
            } else {
                [0.0, 0.0, 1.0]
            }
        })
        .collect()
}

fn raw(value: &serde_json::Value) -> Result<Option<Box<RawValue>>, ExportError> {
    RawValue::from_string(value.to_string())
        .map(Some)
        .map_err(|e| ExportError::Internal(e.to_string()))
}

fn bytes_of(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn bytes_of_u32(values: &[u32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The JSON being built and the binary chunk behind it.
#[derive(Default)]
struct Builder {
    root: json::Root,
    bin: Vec<u8>,
}

impl Builder {
    /// Appends `bytes` (4-byte aligned) as a buffer view.
    fn view(
        &mut self,
        bytes: Vec<u8>,
        target: Option<json::buffer::Target>,
    ) -> Index<json::buffer::View> {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(&bytes);
        self.root.push(json::buffer::View {
            buffer: Index::new(0),
            byte_length: USize64::from(bytes.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            target: target.map(Checked::Valid),
            extensions: None,
            extras: None,
            name: None,
        })
    }

    fn accessor_of(
        &mut self,
        view: Index<json::buffer::View>,
        count: usize,
        type_: json::accessor::Type,
        component: json::accessor::ComponentType,
        bounds: Option<(Vec<f32>, Vec<f32>)>,
    ) -> Index<json::Accessor> {
        let (min, max) = match bounds {
            Some((lo, hi)) => (Some(serde_json::json!(lo)), Some(serde_json::json!(hi))),
            None => (None, None),
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Checked::Valid(json::accessor::GenericComponentType(component)),
            type_: Checked::Valid(type_),
            min,
            max,
            normalized: false,
            sparse: None,
            extensions: None,
            extras: None,
            name: None,
        })
    }

    fn accessor(
        &mut self,
        view: Index<json::buffer::View>,
        count: usize,
        type_: json::accessor::Type,
        bounds: Option<(Vec<f32>, Vec<f32>)>,
    ) -> Index<json::Accessor> {
        self.accessor_of(
            view,
            count,
            type_,
            json::accessor::ComponentType::F32,
            bounds,
        )
    }

    /// A VEC3 float accessor with its bounds (required for positions and their targets).
    fn vec3(
        &mut self,
        values: &[[f32; 3]],
        target: Option<json::buffer::Target>,
    ) -> Index<json::Accessor> {
        let mut lo = vec![f32::INFINITY; 3];
        let mut hi = vec![f32::NEG_INFINITY; 3];
        for v in values {
            for c in 0..3 {
                lo[c] = lo[c].min(v[c]);
                hi[c] = hi[c].max(v[c]);
            }
        }
        let flat: Vec<f32> = values.iter().flatten().copied().collect();
        let view = self.view(bytes_of(&flat), target);
        self.accessor(
            view,
            values.len(),
            json::accessor::Type::Vec3,
            Some((lo, hi)),
        )
    }

    /// A plain float accessor of `values` (`width` per element), bounds when asked.
    fn floats(
        &mut self,
        values: &[f32],
        type_: json::accessor::Type,
        width: usize,
        with_bounds: bool,
    ) -> Index<json::Accessor> {
        let bounds = with_bounds.then(|| {
            let mut lo = vec![f32::INFINITY; width];
            let mut hi = vec![f32::NEG_INFINITY; width];
            for e in values.chunks_exact(width) {
                for c in 0..width {
                    lo[c] = lo[c].min(e[c]);
                    hi[c] = hi[c].max(e[c]);
                }
            }
            (lo, hi)
        });
        let view = self.view(bytes_of(values), None);
        self.accessor(view, values.len() / width, type_, bounds)
    }

    /// The material: the texture as base colour when given, else a light skin grey; matte,
    /// both sides (the face is an open surface).
    fn material(&mut self, texture_png: Option<&[u8]>) -> Index<json::Material> {
        let base_color_texture = texture_png.map(|png| {
            let view = self.view(png.to_vec(), None);
            let image = self.root.push(json::Image {
                buffer_view: Some(view),
                mime_type: Some(json::image::MimeType("image/png".into())),
                uri: None,
                name: Some("texture".into()),
                extensions: None,
                extras: None,
            });
            let sampler = self.root.push(json::texture::Sampler {
                mag_filter: Some(Checked::Valid(json::texture::MagFilter::Linear)),
                min_filter: Some(Checked::Valid(json::texture::MinFilter::LinearMipmapLinear)),
                wrap_s: Checked::Valid(json::texture::WrappingMode::ClampToEdge),
                wrap_t: Checked::Valid(json::texture::WrappingMode::ClampToEdge),
                name: None,
                extensions: None,
                extras: None,
            });
            let texture = self.root.push(json::Texture {
                sampler: Some(sampler),
                source: image,
                name: None,
                extensions: None,
                extras: None,
            });
            json::texture::Info {
                index: texture,
                tex_coord: 0,
                extensions: None,
                extras: None,
            }
        });
        self.root.push(json::Material {
            name: Some("face".into()),
            double_sided: true,
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor(
                    if base_color_texture.is_some() {
                        [1.0; 4]
                    } else {
                        [0.8, 0.72, 0.66, 1.0]
                    },
                ),
                base_color_texture,
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(0.8),
                ..Default::default()
            },
            ..Default::default()
        })
    }

    /// One animation: the targets' weights and the head's motion, linear between key frames.
    fn animation(&mut self, a: &MorphAnimation, node: Index<json::Node>) {
        use json::animation::{Channel, Interpolation, Property, Sampler, Target};
        let times = self.floats(&a.times, json::accessor::Type::Scalar, 1, true);
        let mut outputs = Vec::new();
        if !a.targets.is_empty() {
            let w: Vec<f32> = a.weights.iter().flatten().copied().collect();
            let out = self.floats(&w, json::accessor::Type::Scalar, 1, false);
            outputs.push((out, Property::MorphTargetWeights));
        }
        let t: Vec<f32> = a.translations.iter().flatten().copied().collect();
        let out = self.floats(&t, json::accessor::Type::Vec3, 3, false);
        outputs.push((out, Property::Translation));
        let r: Vec<f32> = a.rotations.iter().flatten().copied().collect();
        let out = self.floats(&r, json::accessor::Type::Vec4, 4, false);
        outputs.push((out, Property::Rotation));
        let samplers = outputs
            .iter()
            .map(|&(output, _)| Sampler {
                input: times,
                interpolation: Checked::Valid(Interpolation::Linear),
                output,
                extensions: None,
                extras: None,
            })
            .collect();
        let channels = outputs
            .into_iter()
            .enumerate()
            .map(|(i, (_, path))| Channel {
                sampler: Index::new(i as u32),
                target: Target {
                    node,
                    path: Checked::Valid(path),
                    extensions: None,
                    extras: None,
                },
                extensions: None,
                extras: None,
            })
            .collect();
        self.root.push(json::Animation {
            name: Some("capture".into()),
            channels,
            samplers,
            extensions: None,
            extras: None,
        });
    }

    /// The GLB container: header, JSON chunk (space-padded), BIN chunk (zero-padded).
    fn finish(mut self) -> Result<Vec<u8>, ExportError> {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.root.buffers = vec![json::Buffer {
            byte_length: USize64::from(self.bin.len()),
            uri: None,
            name: None,
            extensions: None,
            extras: None,
        }];
        let mut text = self
            .root
            .to_vec()
            .map_err(|e| ExportError::Internal(e.to_string()))?;
        while !text.len().is_multiple_of(4) {
            text.push(b' ');
        }
        let total = 12 + 8 + text.len() + 8 + self.bin.len();
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(text.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&text);
        out.extend_from_slice(&(self.bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&self.bin);
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_are_the_renderers_rounded_to_f32_with_plus_z_where_there_is_no_area() {
        // A bumpy 6 × 6 grid, one degenerate triangle and an unused vertex (index 36).
        let n = 6u32;
        let mut v: Vec<[f32; 3]> = (0..n * n)
            .map(|k| {
                let (i, j) = ((k % n) as f32, (k / n) as f32);
                [
                    0.01 * i,
                    0.01 * j,
                    0.003 * (1.3 * i).sin() * (0.7 * j).cos(),
                ]
            })
            .collect();
        v.push([0.5, 0.5, 0.5]);
        let mut t = vec![[0, 0, 1]];
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = j * n + i;
                t.extend([[a, a + 1, a + n + 1], [a, a + n + 1, a + n]]);
            }
        }
        let got = vertex_normals(&v, &t);
        let v64: Vec<[f64; 3]> = v.iter().map(|p| p.map(f64::from)).collect();
        let want = visage_render::vertex_normals(&v64, &t);
        for (g, w) in got.iter().zip(&want).take(36) {
            assert_eq!(g.map(f32::to_bits), w.map(|x| (x as f32).to_bits()));
        }
        assert_eq!(got[36], [0.0, 0.0, 1.0]);
    }
}
