//! The face's colour as a UV texture, fused from several frames: each texel's surface point is
//! projected into every chosen frame through that frame's camera and surface, kept where the
//! point is the visible one (the frame's rendered depth agrees), and averaged in linear light
//! with weight cos²θ (θ between the surface normal and the view ray), so frames that see the
//! skin head-on dominate and grazing views, where the colour smears, hardly count.
//!
//! Texels the frames never saw take the average of their seen neighbours (grown outwards), so
//! the texture has no holes inside the face and a margin around each UV island (no dark seams
//! when a viewer filters across an island's edge).

use image::RgbImage;
use rayon::prelude::*;
use visage_camera::{DepthKind, Intrinsics};
use visage_mesh::color::{linear_to_srgb_u8, srgb_to_linear_u8};
use visage_mesh::TriMesh;
use visage_render::{rasterize_uv_triangle, render_depth, vertex_normals};

use crate::ExportError;

/// Views more oblique than this (cos θ below it) do not colour a texel.
const MIN_COS: f64 = 0.25;
/// A texel's point is visible in a frame when its depth is within this much of the rendered
/// depth there (metres; the surface is sampled from the same mesh, so only rounding and the
/// pixel grid separate them).
const DEPTH_TOLERANCE_M: f64 = 0.003;
/// Texels of margin grown around the seen area.
const MARGIN: usize = 8;

/// A fused texture and what went into it.
pub struct FusedTexture {
    pub image: RgbImage,
    /// Frames that coloured at least one texel.
    pub frames_used: usize,
    /// Share of the mesh's UV area seen by some frame.
    pub coverage: f64,
}

/// One frame for the texture: the surface (camera coordinates) and the image it was seen in.
pub struct TextureView<'a> {
    pub vertices: Vec<[f64; 3]>,
    pub image: &'a RgbImage,
}

/// Where each texel sits on the mesh: its triangle and barycentric coordinates.
struct UvRaster {
    size: usize,
    /// Per texel (row-major, row 0 at v = 1), the triangle and barycentrics, if covered.
    texels: Vec<Option<(u32, [f32; 3])>>,
}

/// Fuses a `size × size` texture for `mesh` (its triangles and UVs) from `views`.
///
/// # Errors
/// The mesh has no UVs; a view's surface cannot be rendered.
pub fn fuse_texture(
    mesh: &TriMesh,
    intrinsics: &Intrinsics,
    views: &[TextureView<'_>],
    size: usize,
) -> Result<FusedTexture, ExportError> {
    if mesh.uvs.len() != mesh.vertices.len() {
        return Err(ExportError::Internal(
            "the mesh has no texture coordinates: no texture can be made".into(),
        ));
    }
    let raster = UvRaster::new(mesh, size);
    let covered: Vec<usize> = (0..raster.texels.len())
        .filter(|&i| raster.texels[i].is_some())
        .collect();
    let linear: [f64; 256] = std::array::from_fn(|c| srgb_to_linear_u8(c as u8) as f64);
    let mut sum = vec![[0.0f64; 4]; covered.len()];
    let mut frames_used = 0;
    for view in views {
        let mut posed = TriMesh::new(view.vertices.clone(), mesh.triangles.clone());
        posed.uvs.clear();
        let depth = render_depth(&posed, intrinsics, None, DepthKind::Z)?;
        let normals = vertex_normals(&view.vertices, &mesh.triangles);
        let k = intrinsics;
        let (w, h) = (k.width as usize, k.height as usize);
        let used = sum
            .par_iter_mut()
            .zip(&covered)
            .map(|(acc, &texel)| {
                let Some((t, b)) = &raster.texels[texel] else {
                    return false;
                };
                let tri = mesh.triangles[*t as usize];
                let mut p = [0.0; 3];
                let mut n = [0.0; 3];
                for (corner, &weight) in tri.iter().zip(b) {
                    for c in 0..3 {
                        p[c] += weight as f64 * view.vertices[*corner as usize][c];
                        n[c] += weight as f64 * normals[*corner as usize][c];
                    }
                }
                if p[2] <= 0.0 {
                    return false;
                }
                let (u, v) = (k.fx * p[0] / p[2] + k.cx, k.fy * p[1] / p[2] + k.cy);
                if !(u >= 0.0 && v >= 0.0 && u <= (w - 1) as f64 && v <= (h - 1) as f64) {
                    return false;
                }
                let at = v.round() as usize * w + u.round() as usize;
                let d = depth.depth.data[at];
                if d <= 0.0 || (d as f64 - p[2]).abs() > DEPTH_TOLERANCE_M {
                    return false;
                }
                let ray_len = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                let n_len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                let cos = ((n[0] * p[0] + n[1] * p[1] + n[2] * p[2]) / (ray_len * n_len)).abs();
                if cos.is_nan() || cos < MIN_COS {
                    return false;
                }
                let weight = cos * cos;
                let rgb = bilinear(view.image, &linear, u, v);
                for c in 0..3 {
                    acc[c] += weight * rgb[c];
                }
                acc[3] += weight;
                true
            })
            .filter(|&seen| seen)
            .count();
        frames_used += usize::from(used > 0);
    }
    let seen = sum.iter().filter(|a| a[3] > 0.0).count();
    let mut colour: Vec<Option<[f64; 3]>> = vec![None; size * size];
    for (a, &i) in sum.iter().zip(&covered) {
        if a[3] > 0.0 {
            colour[i] = Some([a[0] / a[3], a[1] / a[3], a[2] / a[3]]);
        }
    }
    grow(&mut colour, size, &raster, MARGIN);
    let mean = mean_colour(&colour);
    let mut image = RgbImage::new(size as u32, size as u32);
    for (px, c) in image.pixels_mut().zip(&colour) {
        let c = c.unwrap_or(mean);
        px.0 = c.map(|x| linear_to_srgb_u8(x as f32));
    }
    Ok(FusedTexture {
        image,
        frames_used,
        coverage: seen as f64 / covered.len().max(1) as f64,
    })
}

impl UvRaster {
    /// Rasterises the mesh's UV triangles: texel (i, j)'s centre is at
    /// `u = (i + ½) / size`, `v = 1 − (j + ½) / size`.
    fn new(mesh: &TriMesh, size: usize) -> UvRaster {
        let mut texels = vec![None; size * size];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let uv = tri.map(|i| mesh.uvs[i as usize]);
            rasterize_uv_triangle(uv, size, |x, y, b| {
                texels[y * size + x] = Some((t as u32, b.map(|w| w as f32)));
            });
        }
        UvRaster { size, texels }
    }
}

/// Linear RGB at a sub-pixel position (pixel centres at integers); `linear` maps sRGB bytes.
fn bilinear(image: &RgbImage, linear: &[f64; 256], u: f64, v: f64) -> [f64; 3] {
    let (w, h) = (image.width() as usize, image.height() as usize);
    let (x0, y0) = (u.floor() as usize, v.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (u - x0 as f64, v - y0 as f64);
    let px = |x: usize, y: usize| {
        image
            .get_pixel(x as u32, y as u32)
            .0
            .map(|c| linear[c as usize])
    };
    let (a, b, c, d) = (px(x0, y0), px(x1, y0), px(x0, y1), px(x1, y1));
    std::array::from_fn(|k| {
        (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + d[k] * fx) * fy
    })
}

/// Fills unseen texels from their seen neighbours, ring by ring: every texel inside the mesh's
/// UV islands (however far), and `margin` rings beyond them. Each ring visits only the texels
/// next to the last one.
fn grow(colour: &mut [Option<[f64; 3]>], size: usize, raster: &UvRaster, margin: usize) {
    debug_assert_eq!(raster.size, size);
    let neighbours = |i: usize| {
        let (x, y) = (i % size, i / size);
        [
            (x > 0).then(|| i - 1),
            (x + 1 < size).then(|| i + 1),
            (y > 0).then(|| i - size),
            (y + 1 < size).then(|| i + size),
        ]
        .into_iter()
        .flatten()
    };
    let mut queued = vec![false; colour.len()];
    let mut ring: Vec<usize> = Vec::new();
    for i in 0..colour.len() {
        if colour[i].is_none() && neighbours(i).any(|j| colour[j].is_some()) {
            queued[i] = true;
            ring.push(i);
        }
    }
    // Rings since the last one that still filled a texel inside an island.
    let mut outside_rings = 0;
    while !ring.is_empty() && outside_rings <= margin {
        let filled: Vec<(usize, [f64; 3])> = ring
            .iter()
            .map(|&i| {
                let (mut acc, mut n) = ([0.0; 3], 0.0);
                for c in neighbours(i).filter_map(|j| colour[j]) {
                    for k in 0..3 {
                        acc[k] += c[k];
                    }
                    n += 1.0;
                }
                (i, acc.map(|a| a / n))
            })
            .collect();
        let inside = filled.iter().any(|&(i, _)| raster.texels[i].is_some());
        outside_rings = if inside { 0 } else { outside_rings + 1 };
        for &(i, c) in &filled {
            colour[i] = Some(c);
        }
        ring.clear();
        for &(i, _) in &filled {
            for j in neighbours(i) {
                if colour[j].is_none() && !queued[j] {
                    queued[j] = true;
                    ring.push(j);
                }
            }
        }
    }
}

fn mean_colour(colour: &[Option<[f64; 3]>]) -> [f64; 3] {
    let (mut acc, mut n) = ([0.0; 3], 0.0);
    for c in colour.iter().flatten() {
        for k in 0..3 {
            acc[k] += c[k];
        }
        n += 1.0;
    }
    if n == 0.0 {
        [0.5; 3]
    } else {
        acc.map(|a| a / n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 0.2 m square at 1 m facing the camera, UVs over its area, seen in an image whose left
    /// half is red and right half blue: the texture's left half comes out red, its right blue,
    /// and the unseen margin takes the neighbours' colours.
    #[test]
    fn a_square_takes_the_colours_it_is_seen_with() {
        let k = Intrinsics {
            width: 64,
            height: 64,
            fx: 100.0,
            fy: 100.0,
            cx: 31.5,
            cy: 31.5,
        };
        let mut mesh = TriMesh::new(
            vec![
                [-0.1, -0.1, 1.0],
                [0.1, -0.1, 1.0],
                [0.1, 0.1, 1.0],
                [-0.1, 0.1, 1.0],
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        // v up: the square's top edge (y = −0.1, up in the image) at v = 1.
        mesh.uvs = vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
        let image = RgbImage::from_fn(64, 64, |x, _| {
            if x < 32 {
                image::Rgb([255, 0, 0])
            } else {
                image::Rgb([0, 0, 255])
            }
        });
        let view = TextureView {
            vertices: mesh.vertices.clone(),
            image: &image,
        };
        let t = fuse_texture(&mesh, &k, &[view], 32).unwrap();
        assert_eq!(t.frames_used, 1);
        assert!(t.coverage > 0.95, "coverage {}", t.coverage);
        assert_eq!(t.image.get_pixel(4, 16).0, [255, 0, 0]);
        assert_eq!(t.image.get_pixel(27, 16).0, [0, 0, 255]);
        // A view that sees nothing leaves a plain texture, and no frame counted.
        let behind: Vec<[f64; 3]> = mesh.vertices.iter().map(|p| [p[0], p[1], -1.0]).collect();
        let none = TextureView {
            vertices: behind,
            image: &image,
        };
        let t = fuse_texture(&mesh, &k, &[none], 16).unwrap();
        assert_eq!((t.frames_used, t.coverage), (0, 0.0));
    }
}
