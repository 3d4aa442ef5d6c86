//! A whole ICT-FaceKit head rendered as a camera would see it, for benchmarks that run the
//! pipeline on pixels: the face with a real skin texture, the back of the head and neck, the
//! mouth's socket, gums, tongue and teeth, and eyeballs whose irises follow a gaze
//! ([`head_texture`] colours them; ICT's eyelashes are cards that drawn opaque read as a thick
//! black eyeliner, so they are left out with the other overlays), lit mostly by ambient light since the skin texture
//! already carries the clip's light.
//!
//! Set-up ([`HeadRender::new`]) reads the neutral mesh once more with its UVs (vertices copied
//! at UV seams) and matches it corner by corner with the model's triangles, so that each
//! rendered vertex knows its model vertex; per frame ([`HeadRender::render`]) the model's
//! shape `S̄ + Σ identity + Σ expression` is evaluated, each eyeball is turned about its centre
//! by the gaze (ICT-FaceKit's `eyeLook*` shapes move only the lids, not the eyeballs), the
//! head is posed, and the mesh is rasterised by `visage-render`.
//!
//! Pose (camera coordinates: x right, y down, z forward, metres):
//! `x_cam = F · R_head · (x − pivot) + (t_x, t_y, distance + PIVOT_DEPTH_M + t_z)`, `F =
//! diag(1, −1, −1)` (ICT's y-up, +z-facing frame turned to face the camera), `R_head` the
//! head's rotation in the face frame ([`crate::HeadPose`]), `pivot` the identity's neutral
//! face centroid moved [`PIVOT_DEPTH_M`] into the head.

use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;

use image::RgbImage;
use visage_camera::{DepthKind, Intrinsics};
use visage_mesh::color::linear_to_srgb_u8;
use visage_mesh::io::{read_obj_with, ObjReadOptions};
use visage_mesh::TriMesh;
use visage_morphable::{IctModel, ImportOptions, Region};
use visage_render::{Albedo, Camera, Frame, Light, Mat4, Material, Renderer, Scene, Texture, Wrap};
use visage_rig::{live_link_rotation, EyeGaze, ICT_EXPRESSIONS};

use crate::face_texture::face_texture;
use crate::head_pose_track::HeadPose;
use crate::head_texture::{head_texture, paint_lids, EyeLayout, Part, LID_SKIN_M};
use crate::{EvalError, PIVOT_DEPTH_M};

/// The ICT vertex ranges of the head's parts (ICT-FaceKit's README; checked on the OBJ's
/// material groups).
mod ranges {
    use std::ops::Range;
    /// Mouth and eye sockets (inside `M_BackHead`).
    pub const SOCKETS: Range<usize> = 11248..14062;
    pub const GUMS: Range<usize> = 14062..17039;
    pub const TEETH: Range<usize> = 17039..21451;
    /// The subject's left eyeball's outer surface (`M_ScleraLeft`).
    pub const SCLERA_LEFT: Range<usize> = 21451..22221;
    /// The iris meshes inside the eyeballs (hidden behind the sclera's cornea; not drawn).
    pub const IRIS_LEFT: Range<usize> = 22221..23021;
    pub const SCLERA_RIGHT: Range<usize> = 23021..23791;
    pub const IRIS_RIGHT: Range<usize> = 23791..24591;
}

/// Visible iris radius, metres (the horizontal visible iris diameter of an adult, 11.7 mm,
/// which MediaPipe's iris model also assumes).
pub const IRIS_RADIUS_M: f64 = 0.00585;
/// Pupil radius, metres (a 3.6 mm pupil in room light).
pub const PUPIL_RADIUS_M: f64 = 0.0018;
/// Eyeball vertices within this angle of the front fit the iris's place in the UVs.
const EYE_FIT_RAD: f64 = 0.6;

/// Mostly ambient: the texture carries the clip's light; the diffuse part shades a turned
/// head's far side a little. No specular term (the skin texture's highlights are baked in).
const MATERIAL: Material = Material {
    ka: 0.7,
    kd: 0.3,
    ks: 0.0,
    shininess: 1.0,
};

/// The frame's background, linear RGB (a plain mid grey wall).
pub const BACKGROUND: [f32; 3] = [0.20, 0.20, 0.19];

/// The set-up of a head renderer: the model, the render mesh's connectivity and atlas UVs, the
/// texture, the camera.
pub struct HeadRender {
    model: IctModel,
    /// For each rendered vertex, the model vertex it shows.
    source: Vec<u32>,
    triangles: Vec<[u32; 3]>,
    uvs: Vec<[f64; 2]>,
    texture: Texture,
    camera: Camera,
    /// The subject's [left, right] eyeball vertex ranges.
    eyes: [Range<usize>; 2],
    /// Distance of the face centroid from the camera at rest, metres.
    distance_m: f64,
}

impl HeadRender {
    /// A renderer for `model` (every part of the ICT-FaceKit head; expressions in any order)
    /// with the real face texture `face` (square, sRGB, ICT's face UVs), seen through `k` with
    /// the face centroid `distance_m` from the camera at rest.
    ///
    /// # Errors
    /// The neutral mesh cannot be read again with its UVs or does not match the model; a bad
    /// texture, camera or distance.
    pub fn new(
        model: IctModel,
        face: &RgbImage,
        k: Intrinsics,
        distance_m: f64,
    ) -> Result<HeadRender, EvalError> {
        if !(distance_m.is_finite() && distance_m > PIVOT_DEPTH_M) {
            return Err(EvalError::InvalidConfig {
                name: "distance",
                value: distance_m.to_string(),
                reason: "must be finite and beyond the head's rotation centre (0.09 m)",
            });
        }
        let path = model.neutral_path();
        let with_uvs = read_obj_with(&path, &ObjReadOptions::default())?.mesh;
        if with_uvs.uvs.len() != with_uvs.vertices.len()
            || with_uvs.triangles.len() != model.triangles.len()
        {
            return Err(EvalError::InvalidConfig {
                name: "ICT-FaceKit neutral mesh",
                value: path.display().to_string(),
                reason: "its faces with UVs do not match the model's",
            });
        }
        let mut source = Vec::new();
        let mut uvs = Vec::new();
        let mut triangles = Vec::new();
        let mut index: HashMap<(u32, Part), u32> = HashMap::new();
        for (t, u) in model.triangles.iter().zip(&with_uvs.triangles) {
            let Some(part) = part_of(t, with_uvs.uvs[u[0] as usize]) else {
                continue;
            };
            let tri = std::array::from_fn(|c| {
                *index.entry((u[c], part)).or_insert_with(|| {
                    source.push(t[c]);
                    uvs.push(part.atlas_uv(with_uvs.uvs[u[c] as usize]));
                    (source.len() - 1) as u32
                })
            });
            triangles.push(tri);
        }
        let eye = eye_layout(&model, &with_uvs, ranges::SCLERA_LEFT);
        let mut face = face.clone();
        paint_lids(&mut face, &lid_triangles(&model, &with_uvs));
        let texture = head_texture(&face, &eye)?;
        Ok(HeadRender {
            model,
            source,
            triangles,
            uvs,
            texture,
            camera: Camera::new(k)?,
            eyes: [ranges::SCLERA_LEFT, ranges::SCLERA_RIGHT],
            distance_m,
        })
    }

    /// [`HeadRender::new`] with the ICT-FaceKit model in `dir` (every identity mode present,
    /// the 53 expressions in [`visage_rig::ICT_EXPRESSIONS`]' order) and the built-in face
    /// texture ([`crate::face_texture`]).
    ///
    /// # Errors
    /// As [`IctModel::load_with`] and [`HeadRender::new`].
    pub fn load(dir: &Path, k: Intrinsics, distance_m: f64) -> Result<HeadRender, EvalError> {
        let model = IctModel::load_with(
            dir,
            &ImportOptions {
                max_identities: None,
                expressions: Some(ICT_EXPRESSIONS.iter().map(|s| s.to_string()).collect()),
            },
        )?;
        HeadRender::new(model, &face_texture()?, k, distance_m)
    }

    /// The model (identity modes and expressions in its own order).
    pub fn model(&self) -> &IctModel {
        &self.model
    }

    /// The camera's intrinsics.
    pub fn intrinsics(&self) -> &Intrinsics {
        &self.camera.intrinsics
    }

    /// The rotation centre of a head with `identity` (model frame, metres): its neutral face
    /// centroid moved [`PIVOT_DEPTH_M`] back.
    ///
    /// # Errors
    /// Identity weights that do not match the model.
    pub fn pivot(&self, identity: &[f64]) -> Result<[f64; 3], EvalError> {
        let mut shape = Vec::new();
        let none = vec![0.0; self.model.expression_modes.len()];
        self.model.shape(identity, &none, &mut shape)?;
        let face = Region::Face.range();
        let n = face.len() as f64;
        let c = shape[face]
            .iter()
            .fold([0.0; 3], |s, p| [s[0] + p[0], s[1] + p[1], s[2] + p[2]])
            .map(|v| v / n);
        Ok([c[0], c[1], c[2] - PIVOT_DEPTH_M])
    }

    /// The head's model-to-camera transform for `pose`: `x ↦ F R_head (x − pivot) + t`, as
    /// the rotation `F R_head` and the translation `t − F R_head pivot`.
    pub fn camera_from_model(&self, pose: &HeadPose, pivot: [f64; 3]) -> ([[f64; 3]; 3], [f64; 3]) {
        let r_head = live_link_rotation(pose.angles);
        // F = diag(1, −1, −1) flips rows 1 and 2.
        let r: [[f64; 3]; 3] = std::array::from_fn(|i| {
            let s = if i == 0 { 1.0 } else { -1.0 };
            r_head[i].map(|v| s * v)
        });
        let t = [
            pose.shift_m[0],
            pose.shift_m[1],
            self.distance_m + PIVOT_DEPTH_M + pose.shift_m[2],
        ];
        let rp: [f64; 3] = std::array::from_fn(|i| (0..3).map(|k| r[i][k] * pivot[k]).sum());
        (r, std::array::from_fn(|i| t[i] - rp[i]))
    }

    /// Renders the head with `identity` and `expression` weights (the model's orders), the
    /// subject's `[left, right]` eye gazes, posed by `pose` about `pivot`
    /// ([`HeadRender::pivot`]); `work` keeps the buffers between frames.
    ///
    /// # Errors
    /// Weights that do not match the model; a failing render.
    pub fn render(
        &self,
        identity: &[f64],
        expression: &[f64],
        gaze: [EyeGaze; 2],
        pose: &HeadPose,
        pivot: [f64; 3],
        work: &mut RenderWork,
    ) -> Result<RgbImage, EvalError> {
        self.model.shape(identity, expression, &mut work.shape)?;
        for (eye, g) in self.eyes.iter().zip(gaze) {
            turn_eye(&mut work.shape[eye.clone()], g);
        }
        let (r, t) = self.camera_from_model(pose, pivot);
        work.mesh.vertices.clear();
        work.mesh.vertices.extend(self.source.iter().map(|&i| {
            let p = work.shape[i as usize];
            std::array::from_fn(|row| (0..3).map(|k| r[row][k] * p[k]).sum::<f64>() + t[row])
        }));
        if work.mesh.triangles.is_empty() {
            work.mesh.triangles = self.triangles.clone();
            work.mesh.uvs = self.uvs.clone();
        }
        let k = self.camera.intrinsics;
        let frame = work
            .frame
            .get_or_insert_with(|| Frame::color_and_depth(k.width, k.height, DepthKind::Z));
        let scene = Scene {
            material: MATERIAL,
            light: Light::white([0.0, -0.3, -1.0]),
            albedo: Albedo::Texture {
                texture: &self.texture,
                wrap: Wrap::Clamp,
            },
            background: BACKGROUND,
            ..Scene::default()
        };
        work.renderer
            .render(&work.mesh, &self.camera, &Mat4::IDENTITY, &scene, frame)?;
        let bytes = frame
            .color
            .iter()
            .flat_map(|p| p.map(linear_to_srgb_u8))
            .collect();
        RgbImage::from_raw(k.width, k.height, bytes).ok_or(EvalError::InvalidConfig {
            name: "frame",
            value: format!("{}×{}", k.width, k.height),
            reason: "the render does not fill the image",
        })
    }
}

/// Buffers a [`HeadRender`] reuses from frame to frame.
#[derive(Default)]
pub struct RenderWork {
    shape: Vec<[f64; 3]>,
    mesh: TriMesh,
    renderer: Renderer,
    frame: Option<Frame>,
}

/// The part a model triangle `t` (model vertex indices) belongs to, from its vertices' ranges
/// and its first corner's UV tile; `None` for what is not drawn (the inner iris meshes, the
/// overlays: tear film, eye blend and occlusion, eyelashes).
fn part_of(t: &[u32; 3], uv: [f64; 2]) -> Option<Part> {
    let v = t[0] as usize;
    let all_in = |r: Range<usize>| t.iter().all(|&i| r.contains(&(i as usize)));
    let any_in = |r: Range<usize>| t.iter().any(|&i| r.contains(&(i as usize)));
    if any_in(ranges::SCLERA_LEFT) || any_in(ranges::SCLERA_RIGHT) {
        return Some(Part::Eye);
    }
    if any_in(ranges::IRIS_LEFT) || any_in(ranges::IRIS_RIGHT) {
        return None;
    }
    if v >= ranges::IRIS_RIGHT.end {
        return None;
    }
    if any_in(ranges::TEETH) {
        return Some(Part::Teeth);
    }
    if any_in(ranges::GUMS) {
        return Some(Part::Gums);
    }
    if any_in(ranges::SOCKETS) {
        return Some(Part::Socket);
    }
    if uv[0] < 1.0 && all_in(Region::Face.range()) {
        return Some(Part::Face);
    }
    Some(Part::Scalp)
}

/// The face triangles' UVs with, per corner, how far a blink moves it (the larger of
/// `eyeBlink_L` and `eyeBlink_R`'s displacement, metres); empty without those expressions.
fn lid_triangles(model: &IctModel, with_uvs: &TriMesh) -> Vec<([[f64; 2]; 3], [f64; 3])> {
    let blinks: Vec<&Vec<[f64; 3]>> = ["eyeBlink_L", "eyeBlink_R"]
        .iter()
        .filter_map(|n| model.expression_index(n))
        .map(|i| &model.expression_modes[i])
        .collect();
    if blinks.is_empty() {
        return Vec::new();
    }
    let moved = |v: u32| {
        blinks
            .iter()
            .map(|b| visage_camera::vec3::norm(b[v as usize]))
            .fold(0.0, f64::max)
    };
    model
        .triangles
        .iter()
        .zip(&with_uvs.triangles)
        .filter(|(t, u)| part_of(t, with_uvs.uvs[u[0] as usize]) == Some(Part::Face))
        .map(|(t, u)| (u.map(|j| with_uvs.uvs[j as usize]), t.map(moved)))
        .filter(|(_, d)| d.iter().any(|&d| d > LID_SKIN_M.0))
        .collect()
}

/// The eyeball's centre: the middle of its vertices' bounding box.
fn eye_centre(vertices: &[[f64; 3]]) -> [f64; 3] {
    let (lo, hi) = vertices
        .iter()
        .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
            (
                std::array::from_fn(|c| lo[c].min(p[c])),
                std::array::from_fn(|c| hi[c].max(p[c])),
            )
        });
    std::array::from_fn(|c| 0.5 * (lo[c] + hi[c]))
}

/// Turns an eyeball's vertices (model frame) about its centre so that its front (+z) looks
/// along the gaze: `R_y(yaw) R_x(−pitch)`, the direction
/// `(cos p sin y, sin p, cos p cos y)` of [`visage_rig::eye_gaze`]'s convention.
fn turn_eye(vertices: &mut [[f64; 3]], gaze: EyeGaze) {
    let c = eye_centre(vertices);
    let (sy, cy) = gaze.yaw.sin_cos();
    let (sp, cp) = (-gaze.pitch).sin_cos();
    let r_y = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]];
    let r_x = [[1.0, 0.0, 0.0], [0.0, cp, -sp], [0.0, sp, cp]];
    let r: [[f64; 3]; 3] = std::array::from_fn(|i| {
        std::array::from_fn(|j| (0..3).map(|k| r_y[i][k] * r_x[k][j]).sum())
    });
    for p in vertices {
        let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
        *p = std::array::from_fn(|i| c[i] + (0..3).map(|k| r[i][k] * d[k]).sum::<f64>());
    }
}

/// Where the iris goes in the eyeball's UVs (see [`EyeLayout`]): the front vertex's UV, and
/// the least-squares slope of UV distance from it against the angle from the front, over the
/// vertices within [`EYE_FIT_RAD`]; the iris and pupil radii as angles on the eyeball's
/// sphere (its mean radius about the centre).
fn eye_layout(model: &IctModel, with_uvs: &TriMesh, sclera: Range<usize>) -> EyeLayout {
    // One UV per model vertex (the first corner's).
    let mut uv_of = vec![None; model.vertex_count()];
    for (t, u) in model.triangles.iter().zip(&with_uvs.triangles) {
        for (&i, &j) in t.iter().zip(u) {
            uv_of[i as usize].get_or_insert(with_uvs.uvs[j as usize]);
        }
    }
    let vertices = &model.neutral[sclera.clone()];
    let c = eye_centre(vertices);
    let radius = vertices
        .iter()
        .map(|p| visage_camera::vec3::distance(*p, c))
        .sum::<f64>()
        / vertices.len() as f64;
    let front = sclera
        .clone()
        .max_by(|&a, &b| model.neutral[a][2].total_cmp(&model.neutral[b][2]))
        .unwrap_or(sclera.start);
    let front_uv = uv_of[front].unwrap_or([0.5, 0.5]);
    let (mut num, mut den) = (0.0, 0.0);
    for i in sclera {
        let Some(uv) = uv_of[i] else { continue };
        let d = visage_camera::vec3::sub(model.neutral[i], c);
        let theta = (d[2] / visage_camera::vec3::norm(d))
            .clamp(-1.0, 1.0)
            .acos();
        if theta < EYE_FIT_RAD {
            let rho = ((uv[0] - front_uv[0]).powi(2) + (uv[1] - front_uv[1]).powi(2)).sqrt();
            num += rho * theta;
            den += theta * theta;
        }
    }
    let on_sphere = |r: f64| (r / radius).clamp(0.0, 1.0).asin();
    EyeLayout {
        front_uv,
        uv_per_rad: if den > 0.0 { num / den } else { 0.25 },
        iris_rad: on_sphere(IRIS_RADIUS_M),
        pupil_rad: on_sphere(PUPIL_RADIUS_M),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_eye_turns_about_its_centre_toward_the_gaze() {
        // A ring of points around +z and the front point.
        let mut eye: Vec<[f64; 3]> = (0..8)
            .map(|k| {
                let a = k as f64 * std::f64::consts::FRAC_PI_4;
                [0.01 * a.cos(), 0.01 * a.sin(), 0.0]
            })
            .collect();
        eye.push([0.0, 0.0, 0.01]);
        eye.push([0.0, 0.0, -0.01]);
        let gaze = EyeGaze {
            yaw: 0.3,
            pitch: 0.2,
        };
        turn_eye(&mut eye, gaze);
        let front = eye[8];
        let expected = [
            0.01 * gaze.pitch.cos() * gaze.yaw.sin(),
            0.01 * gaze.pitch.sin(),
            0.01 * gaze.pitch.cos() * gaze.yaw.cos(),
        ];
        for c in 0..3 {
            assert!(
                (front[c] - expected[c]).abs() < 1e-12,
                "{front:?} vs {expected:?}"
            );
        }
        // visage-rig's own reading of that direction gives the gaze back.
        assert!((front[0].atan2(front[2]) - gaze.yaw).abs() < 1e-12);
        assert!(((front[1] / 0.01).asin() - gaze.pitch).abs() < 1e-12);
    }

    #[test]
    fn triangles_are_sorted_into_parts_by_their_vertices() {
        assert_eq!(part_of(&[10, 11, 12], [0.3, 0.3]), Some(Part::Face));
        assert_eq!(part_of(&[9500, 9501, 9502], [1.3, 0.3]), Some(Part::Scalp));
        assert_eq!(
            part_of(&[12000, 12001, 12002], [1.3, 0.3]),
            Some(Part::Socket)
        );
        assert_eq!(
            part_of(&[15000, 15001, 15002], [2.3, 0.3]),
            Some(Part::Gums)
        );
        assert_eq!(
            part_of(&[18000, 18001, 18002], [3.3, 0.3]),
            Some(Part::Teeth)
        );
        assert_eq!(part_of(&[21500, 21501, 21502], [0.3, 0.3]), Some(Part::Eye));
        assert_eq!(part_of(&[22500, 22501, 22502], [0.3, 0.3]), None);
        assert_eq!(part_of(&[24700, 24701, 24702], [4.3, 0.3]), None);
        assert_eq!(part_of(&[26000, 26001, 26002], [6.3, 0.3]), None);
    }
}
