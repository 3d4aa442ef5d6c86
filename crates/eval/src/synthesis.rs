//! Seeded synthesis of ground-truth face sequences from the ICT-FaceKit model.
//!
//! Per sequence: identity weights ~ N(0, 1); per blendshape a smooth trajectory in [0, 1]
//! (keyframes, most of them 0: a face is neutral most of the time); head yaw in
//! ±`max_yaw_deg`, pitch in ±`max_pitch_deg`, translation in ±`max_translation_m` per axis,
//! with still segments; the face's centroid at a distance drawn from `distance_m`. Every frame's
//! mesh is rendered with `visage_render::render_depth` into exact z-depth and a triangle-id
//! buffer, from which the face-region mask (pixels that see a [`Region::Face`] triangle) is read.
//!
//! Frames (camera coordinates, the project's: x right, y down, z forward, metres):
//! `x_cam = R_c · R_head · (x_model − pivot) + (t_x, t_y, distance + PIVOT_DEPTH_M + t_z)`, with
//! `R_c = diag(1, −1, −1)` (ICT's y-up, +z-facing model turned to face the camera),
//! `R_head = R_y(yaw) · R_x(pitch)` and `pivot` = the neutral face centroid moved
//! [`PIVOT_DEPTH_M`] into the head (the head turns about its centre, not about the nose).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_mesh::{Mask, TriMesh};
use visage_morphable::{IctModel, Region, SOLID_SURFACE_END};
use visage_render::{render_depth, Camera, Frame, Mat4, Renderer, Scene, NO_TRIANGLE};

use crate::normal::standard_normal;
use crate::trajectory::keyframe_trajectory;
use crate::EvalError;

/// Depth of the head's rotation centre behind the face centroid, metres.
pub const PIVOT_DEPTH_M: f64 = 0.09;

/// Probability that an expression keyframe is non-zero.
pub const EXPRESSION_ACTIVITY: f64 = 0.3;

/// What to synthesise. Defaults: 320×240 pixels, f = 350 px (49° horizontal field of view), 120
/// frames, face 0.4–0.8 m from the camera, yaw ±25°, pitch ±10°, translation ±3 cm.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SynthesisConfig {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Focal length f_x = f_y, pixels; principal point at the image centre.
    pub focal_px: f64,
    /// Frames per sequence.
    pub frames: usize,
    /// Range of the face centroid's distance from the camera, metres.
    pub distance_m: (f64, f64),
    /// Largest head yaw (about the vertical axis), degrees.
    pub max_yaw_deg: f64,
    /// Largest head pitch, degrees.
    pub max_pitch_deg: f64,
    /// Largest head translation per axis, metres.
    pub max_translation_m: f64,
    /// Probability that a motion segment is still.
    pub still_probability: f64,
}

impl Default for SynthesisConfig {
    fn default() -> Self {
        SynthesisConfig {
            width: 320,
            height: 240,
            focal_px: 350.0,
            frames: 120,
            distance_m: (0.4, 0.8),
            max_yaw_deg: 25.0,
            max_pitch_deg: 10.0,
            max_translation_m: 0.03,
            still_probability: 0.3,
        }
    }
}

impl SynthesisConfig {
    /// The camera: square pixels, principal point at the image centre.
    pub fn intrinsics(&self) -> Result<Intrinsics, EvalError> {
        let (cx, cy) = (
            (self.width as f64 - 1.0) / 2.0,
            (self.height as f64 - 1.0) / 2.0,
        );
        Ok(Intrinsics::new(
            self.width,
            self.height,
            self.focal_px,
            self.focal_px,
            cx,
            cy,
        )?)
    }

    /// Errors on values outside their documented ranges.
    pub fn validate(&self) -> Result<(), EvalError> {
        let bad =
            |name: &'static str, value: String, reason: &'static str| EvalError::InvalidConfig {
                name,
                value,
                reason,
            };
        if self.frames < 2 {
            return Err(bad(
                "frames",
                self.frames.to_string(),
                "need at least 2 frames",
            ));
        }
        let (lo, hi) = self.distance_m;
        if !(lo.is_finite() && hi.is_finite() && lo > PIVOT_DEPTH_M && lo <= hi) {
            return Err(bad(
                "distance",
                format!("{lo}..{hi}"),
                "must be a finite range beyond 0.09 m",
            ));
        }
        for (name, v) in [
            ("max-yaw", self.max_yaw_deg),
            ("max-pitch", self.max_pitch_deg),
            ("max-translation", self.max_translation_m),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(name, v.to_string(), "must be finite and non-negative"));
            }
        }
        if !(0.0..=1.0).contains(&self.still_probability) {
            return Err(bad(
                "still-probability",
                self.still_probability.to_string(),
                "must lie in [0, 1]",
            ));
        }
        self.intrinsics()?;
        Ok(())
    }
}

/// One ground-truth frame.
#[derive(Clone, Debug)]
pub struct SyntheticFrame {
    /// Vertices `0..SOLID_SURFACE_END` of the posed mesh, camera coordinates, metres.
    pub vertices: Vec<[f64; 3]>,
    /// Exact z-depth of the mesh at each pixel centre, metres, 0 = background.
    pub depth: DepthMap,
    /// Pixels whose visible triangle has all three vertices in [`Region::Face`].
    pub face: Mask,
    /// Head yaw and pitch, degrees.
    pub yaw_deg: f64,
    pub pitch_deg: f64,
    /// Head translation, metres (camera axes).
    pub translation: [f64; 3],
    /// Blendshape weights, in the model's expression order, each in [0, 1].
    pub expression: Vec<f64>,
}

/// A synthesised sequence: camera, shared triangles and per-frame ground truth.
#[derive(Clone, Debug)]
pub struct SyntheticSequence {
    pub k: Intrinsics,
    /// The seed it was drawn from.
    pub seed: u64,
    /// Face centroid distance at rest, metres.
    pub distance_m: f64,
    /// Identity weights (N(0, 1) draws).
    pub identity: Vec<f64>,
    /// Triangles of the rendered surface (vertices `0..SOLID_SURFACE_END`).
    pub triangles: Vec<[u32; 3]>,
    pub frames: Vec<SyntheticFrame>,
}

impl SyntheticSequence {
    /// The ground-truth mesh of frame `index` (camera coordinates, metres).
    ///
    /// # Panics
    /// If `index` is not a frame.
    #[track_caller]
    pub fn mesh(&self, index: usize) -> TriMesh {
        TriMesh::new(self.frames[index].vertices.clone(), self.triangles.clone())
    }

    /// A shaded colour image (linear RGB, row-major) of frame `index`, rendered by the project's
    /// renderer (Algorithm 3: Blinn–Phong, default light and a skin-like constant albedo).
    pub fn render_color(&self, index: usize) -> Result<Vec<[f32; 3]>, EvalError> {
        self.render_color_with(index, None)
    }

    /// [`SyntheticSequence::render_color`] with, when given, one linear RGB albedo per vertex
    /// of the rendered surface (`vertex_colors`, interpolated across triangles) instead of the
    /// constant one.
    ///
    /// # Errors
    /// A failing render, or `vertex_colors` of another length than the frame's vertices.
    pub fn render_color_with(
        &self,
        index: usize,
        vertex_colors: Option<&[[f32; 3]]>,
    ) -> Result<Vec<[f32; 3]>, EvalError> {
        let camera = Camera::new(self.k)?;
        let mut mesh = self.mesh(index);
        let albedo = match vertex_colors {
            Some(colors) => {
                if colors.len() != mesh.vertices.len() {
                    return Err(EvalError::InvalidConfig {
                        name: "vertex_colors",
                        value: colors.len().to_string(),
                        reason: "need one colour per vertex of the rendered surface",
                    });
                }
                mesh.colors = colors.to_vec();
                visage_render::Albedo::VertexColors
            }
            None => visage_render::Albedo::Constant(SKIN_ALBEDO),
        };
        let scene = Scene {
            albedo,
            ..Scene::default()
        };
        let mut frame = Frame::color_and_depth(self.k.width, self.k.height, DepthKind::Z);
        Renderer::new().render(&mesh, &camera, &Mat4::IDENTITY, &scene, &mut frame)?;
        Ok(frame.color)
    }

    /// The vertices of frame `index` in head coordinates (metres): the camera-space mesh with
    /// the frame's head pose undone, `R_c · (x_model − pivot)` in the module's notation — fixed
    /// to the face, so a function of them is a texture that moves with the skin (up to the
    /// frame's expression).
    ///
    /// # Panics
    /// If `index` is not a frame.
    #[track_caller]
    pub fn head_coordinates(&self, index: usize) -> Vec<[f64; 3]> {
        let f = &self.frames[index];
        let r = mul(rotation_y(f.yaw_deg), rotation_x(f.pitch_deg));
        let t = [
            f.translation[0],
            f.translation[1],
            self.distance_m + PIVOT_DEPTH_M + f.translation[2],
        ];
        // x_cam = R_c · R_head · d + t, R_c R_head = R_h' R_c with R_h' = R_c R_head R_c; so
        // R_c · d = R_h'ᵀ · (x_cam − t).
        let r_c = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]];
        let r_h = mul(r_c, mul(r, r_c));
        f.vertices
            .iter()
            .map(|p| {
                let d = [p[0] - t[0], p[1] - t[1], p[2] - t[2]];
                std::array::from_fn(|i| r_h[0][i] * d[0] + r_h[1][i] * d[1] + r_h[2][i] * d[2])
            })
            .collect()
    }
}

/// The linear RGB albedo of [`SyntheticSequence::render_color`]: a light skin tone.
pub const SKIN_ALBEDO: [f32; 3] = [0.8, 0.6, 0.5];

fn rotation_y(deg: f64) -> [[f64; 3]; 3] {
    let (s, c) = deg.to_radians().sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

fn rotation_x(deg: f64) -> [[f64; 3]; 3] {
    let (s, c) = deg.to_radians().sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

fn mul(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// Synthesises one sequence from `model` with `config`, deterministically from `seed`.
///
/// # Errors
/// Invalid configuration, weights inconsistent with the model, a rendering failure, or a face
/// that leaves the image entirely.
pub fn synthesize(
    model: &IctModel,
    config: &SynthesisConfig,
    seed: u64,
) -> Result<SyntheticSequence, EvalError> {
    config.validate()?;
    let k = config.intrinsics()?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n_frames = config.frames;
    let identity: Vec<f64> = (0..model.identity_modes.len())
        .map(|_| standard_normal(&mut rng))
        .collect();
    let distance_m = rng.random_range(config.distance_m.0..=config.distance_m.1);
    let expressions: Vec<Vec<f64>> = (0..model.expression_modes.len())
        .map(|_| {
            keyframe_trajectory(&mut rng, n_frames, 0.0, &mut |r| {
                if r.random::<f64>() < EXPRESSION_ACTIVITY {
                    r.random::<f64>()
                } else {
                    0.0
                }
            })
        })
        .collect();
    let symmetric = |rng: &mut ChaCha8Rng, max: f64| {
        keyframe_trajectory(rng, n_frames, config.still_probability, &mut |r| {
            if max > 0.0 {
                r.random_range(-max..=max)
            } else {
                0.0
            }
        })
    };
    let yaw = symmetric(&mut rng, config.max_yaw_deg);
    let pitch = symmetric(&mut rng, config.max_pitch_deg);
    let shift: Vec<Vec<f64>> = (0..3)
        .map(|_| symmetric(&mut rng, config.max_translation_m))
        .collect();

    let face = Region::Face.range();
    let centroid = model.neutral[face.clone()]
        .iter()
        .fold([0.0; 3], |s, p| [s[0] + p[0], s[1] + p[1], s[2] + p[2]])
        .map(|c| c / face.len() as f64);
    let pivot = [centroid[0], centroid[1], centroid[2] - PIVOT_DEPTH_M];
    let r_c = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]];
    let triangles = model.triangles_below(SOLID_SURFACE_END);
    let face_triangle: Vec<bool> = triangles
        .iter()
        .map(|t| t.iter().all(|&i| Region::Face.contains(i as usize)))
        .collect();

    let mut shape = Vec::with_capacity(model.vertex_count());
    let mut mesh = TriMesh::new(Vec::new(), triangles.clone());
    let mut frames = Vec::with_capacity(n_frames);
    for f in 0..n_frames {
        let expression: Vec<f64> = expressions.iter().map(|e| e[f].clamp(0.0, 1.0)).collect();
        model.shape(&identity, &expression, &mut shape)?;
        let r = mul(r_c, mul(rotation_y(yaw[f]), rotation_x(pitch[f])));
        let t = [
            shift[0][f],
            shift[1][f],
            distance_m + PIVOT_DEPTH_M + shift[2][f],
        ];
        mesh.vertices.clear();
        mesh.vertices
            .extend(shape[..SOLID_SURFACE_END].iter().map(|p| {
                let d = [p[0] - pivot[0], p[1] - pivot[1], p[2] - pivot[2]];
                std::array::from_fn(|i| r[i][0] * d[0] + r[i][1] * d[1] + r[i][2] * d[2] + t[i])
            }));
        let render = render_depth(&mesh, &k, None, DepthKind::Z)?;
        let face_mask = Mask {
            width: k.width,
            height: k.height,
            data: render
                .triangle_id
                .iter()
                .map(|&id| id != NO_TRIANGLE && face_triangle[id as usize])
                .collect(),
        };
        if face_mask.count() == 0 {
            return Err(EvalError::Degenerate {
                seed,
                reason: format!("frame {f}: the face is outside the image"),
            });
        }
        frames.push(SyntheticFrame {
            vertices: mesh.vertices.clone(),
            depth: render.depth,
            face: face_mask,
            yaw_deg: yaw[f],
            pitch_deg: pitch[f],
            translation: [shift[0][f], shift[1][f], shift[2][f]],
            expression,
        });
    }
    Ok(SyntheticSequence {
        k,
        seed,
        distance_m,
        identity,
        triangles,
        frames,
    })
}
