//! Face-anchored fusion with a pose-compensated temporal term (ERRATA 15–18).
//!
//! The paper's mesh is fixed on the image plane and its temporal term `μ‖S_k − S_{k−1}‖²_M`
//! pulls the surface towards where the face *was*. Here every vertex is a fixed point of the
//! face ([`FaceDomain`]), and the temporal term follows the head:
//!
//! ```text
//! E(S_k) = ‖S_k − X_k‖²_M + λ (S_k − P_k)ᵀ K (S_k − P_k) + μ ‖S_k − T_k T_{k−1}⁻¹ S_{k−1}‖²_M
//! ```
//!
//! with `X_k` the raw surface sampled at the vertices (the data term, Eq. 2.2), `T_k` the rigid
//! head pose of frame k (head → camera, from the metric face fit), `P_k = T_k C` the template
//! `C` placed by the pose, `M` the consistent mass and `K = Lᵀ M_l⁻¹ L` the biharmonic
//! stiffness (Eq. 2.4, ERRATA 3) of the template surface.
//!
//! **The matrix does not depend on the pose.** M and K act on each coordinate column
//! separately, so for a rigid motion `T x = R x + t` applied to every vertex
//! (`T S = S Rᵀ + 1 tᵀ`): `‖T A − T B‖²_M = tr(R (A−B)ᵀ M (A−B) Rᵀ) = ‖A − B‖²_M`, and
//! `K (T A − T B) = K (A − B) Rᵀ` so the smoothness term is invariant too. Writing every frame
//! in head coordinates, `S̃_k = T_k⁻¹ S_k`, `X̃_k = T_k⁻¹ X_k`, the energy becomes
//!
//! ```text
//! E = ‖S̃_k − X̃_k‖²_M + λ (S̃_k − C)ᵀ K (S̃_k − C) + μ ‖S̃_k − S̃_{k−1}‖²_M ,
//! ```
//!
//! the paper's energy with a data mass `M` (ERRATA's `((1+μ)M + λK) s = …`) and a template
//! prior. The solver works on the deviation from the template, `D_k = S̃_k − C`: the streaming
//! step solves `((1+μ)M + λK) D_k = M (X̃_k − C) + μ M D_{k−1}` with the matrix factored once
//! per clip, and `S_k = T_k (C + D_k)`. Only the right-hand side moves with the head; the clip
//! mode is [`visage_fem::solve_clip`] on the same right-hand sides.
//!
//! **A template per frame.** When each frame brings its own template `C_k` — the morphable
//! model fitted to the frame, with this person's identity and the frame's expression — the
//! prior and the temporal term both act on the deviation from it:
//! `λ D_kᵀ K D_k + μ ‖D_k − D_{k−1}‖²_M` with `D_k = S̃_k − C_k`. The model's own motion (an
//! opening mouth, a blink) then passes through without lag; only what the data add to the
//! model is smoothed over time. The operators stay those of the fixed template the fuser was
//! built on (the frame's template has the same connectivity and nearly the same metric).
//!
//! **Why the template prior** (`S − P` rather than `S` in the smoothness term): on a curved
//! face, `ΔS` of the face itself is its mean-curvature normal, so `λ‖ΔS‖²` flattens the nose
//! and shrinks the outline; smoothing the deviation from the posed template removes noise and
//! keeps the face's shape. Constants are in K's null space, so `K P_k = K C Rᵀ`: the prior's
//! right-hand side is computed once.
//!
//! **The face's size.** The landmark fit places the template (an average adult face) at the
//! distance where it projects like the landmarks, so a larger face is placed too close — and
//! the fitted distance drifts with the head's yaw when the face's shape differs from the
//! template. With the face CNN's surface the data share that scale and nothing is needed; a
//! depth map measures it: every frame the median ratio of sampled to template ray distances
//! updates a filtered scale `s` ([`SCALE_FILTER_RATIO`]), and the pose used is the fitted one with
//! its translation times `s` (the template scaled about the camera centre projects exactly as
//! before) and the template `s·C` (`s·C_k`).
//!
//! **Units.** The finite-element domain is the template surface in millimetres (the
//! canonical FaceMesh is an average adult face), so λ is in mm⁴: smoothing length ≈ λ^{1/4} mm.
//! Vertex fields are metres.

use std::time::Instant;

use faer::Mat;
use visage_camera::vec3::norm;
use visage_camera::{DepthMap, Intrinsics, RigidTransform};
use visage_fem::{
    biharmonic, cotan_laplacian, lumped_mass, mass_matrix, FusionSystem, Operators,
    StreamingSolver, SurfaceMetrics, SurfaceQuality, Weights,
};

use visage_temporal::{ConstantVelocity, TrackFilter};

use crate::{ClipState, FaceDomain, FrameStatus, FusedFrame, FusionError, SurfaceFuser};

/// Template coordinates (metres) → finite-element domain coordinates (millimetres).
pub const DOMAIN_UNITS_PER_METRE: f64 = 1000.0;

/// Default λ (mm⁴) and μ of the face-anchored fusion on the face CNN's surface. That surface is
/// already smooth (planar over each FaceMesh triangle), so λ only pulls the landmarks towards
/// the template, and it flattens the lips' edges most (at λ = 1 the inner lips sit 0.7 px from
/// the tracked ones against 0.09 px for the face); the temporal smoothing is the landmark
/// smoother's, before the fit, so μ = 0 here (μ = 0.5 on top of it adds lag to the mouth for
/// a little less jitter; docs/performance.md, "Temporal stability").
pub const ANCHORED_WEIGHTS_FACE: Weights = Weights {
    lambda: 0.1,
    mu: 0.0,
};

/// Default λ (mm⁴) and μ of the face-anchored fusion on depth maps (a sensor, a depth network):
/// the best RMSE of the ground-truth benchmark's sweep with CNN-like depth noise
/// (`visage eval synthetic --sweep-method face_anchored`).
pub const ANCHORED_WEIGHTS_MAP: Weights = Weights {
    lambda: 10.0,
    mu: 1.0,
};

/// Default λ (mm⁴ of the model's face) and μ of the fusion on the fitted morphable model's mesh
/// with depth maps: the best RMSE of the ground-truth benchmark's sweep (λ 10³–10⁵, μ 2–8;
/// `visage eval synthetic --sweep-method model_fusion`). It is no better than the fitted face
/// alone there (docs/performance.md): the depth maps' noise is as large as the fit's error.
pub const MODEL_WEIGHTS_MAP: Weights = Weights {
    lambda: 1000.0,
    mu: 2.0,
};

/// Acceleration-to-noise ratio (1/s², frames taken 1/30 s apart) of the constant-velocity
/// filter on the face's scale (see [`AnchoredFuser::scale`]). The landmark fit's distance
/// drifts with the head's yaw when the face's shape differs from the template (up to 9 % over
/// 24 frames on the benchmark), so the scale is re-measured every frame; the filter keeps the
/// depth maps' per-frame flicker out of the head pose and follows the drift without lag. On the
/// quick benchmark it took the fitted model's RMSE from 1.88 to 1.51 mm and its jitter from
/// 1.70 to 1.35 mm against the exponential average it replaced (weight 0.5; ratio 3: 1.62 mm,
/// 1.33 mm).
pub const SCALE_FILTER_RATIO: f64 = 30.0;

/// The frame interval the scale filter assumes, seconds.
const SCALE_FRAME_INTERVAL_S: f64 = 1.0 / 30.0;

/// Where a frame's raw surface comes from.
#[derive(Clone, Copy, Debug)]
pub enum FrameDepth<'a> {
    /// A triangulated surface with one camera-space point (metres) per template vertex that
    /// projects onto that vertex's landmark — the face CNN's metric landmarks. A vertex's raw
    /// point is where its pixel's ray meets its template triangle (perspective-correct
    /// interpolation): exactly what rasterising the surface and sampling the depth map at the
    /// vertex's pixel gives, without rasterising.
    Surface(&'a [[f64; 3]]),
    /// A depth map (z or ray distance, metres; `0`/NaN = none), sampled bilinearly at the
    /// vertex's pixel: an RGB-D sensor, a depth network, or the benchmark's noisy depth.
    Map(&'a DepthMap),
}

/// One frame's input.
#[derive(Clone, Copy, Debug)]
pub struct AnchoredFrame<'a> {
    /// Pixel position of every template vertex (e.g. the 468 tracked landmarks).
    pub landmarks_px: &'a [[f64; 2]],
    /// Head pose `T_k`: template (head) coordinates → camera coordinates.
    pub pose: RigidTransform,
    pub depth: FrameDepth<'a>,
    /// This frame's template `C_k` (head coordinates, metres, one point per template vertex),
    /// e.g. the morphable model fitted to the frame; `None`: the fixed template the fuser was
    /// built on.
    pub template: Option<&'a [[f64; 3]]>,
}

/// Streaming face-anchored fusion: the fixed mesh, its factored system and per-frame buffers
/// (allocated once; [`AnchoredFuser::process`] allocates nothing).
pub struct AnchoredFuser {
    domain: FaceDomain,
    k: Intrinsics,
    max_depth: f64,
    solver: StreamingSolver,
    metrics: SurfaceMetrics,
    /// Template positions at the vertices, head coordinates, metres (`C`).
    rest: Mat<f64>,
    /// The frame's template at the face's scale, head coordinates (`s C_k`): the solver works
    /// on the deviation `S̃_k − s C_k`.
    offset: Mat<f64>,
    /// Scratch: a frame's template interpolated at the domain vertices.
    frame_template: Vec<[f64; 3]>,
    pixels: Vec<[f64; 2]>,
    raw: Vec<[f64; 3]>,
    valid: Vec<bool>,
    /// The data's deviation from the frame's template, head coordinates, holes filled
    /// (`X̃_k − s C_k`).
    data: Mat<f64>,
    b: Mat<f64>,
    /// The last solution's deviation from the frame's template, head coordinates (`D_k`).
    deviation: Mat<f64>,
    solution: Vec<[f64; 3]>,
    pose: RigidTransform,
    /// Face size relative to the template (1 until a depth map measures it).
    scale: f64,
    /// The filter the per-frame scale measurements go through.
    scale_filter: ConstantVelocity,
    /// Scratch for the per-frame median, #V.
    ratios: Vec<f64>,
}

impl AnchoredFuser {
    /// Builds the operators on the template surface (`template` = head-coordinate positions of
    /// the template vertices, metres) and factors the frame matrices once.
    pub fn new(
        domain: FaceDomain,
        template: &[[f64; 3]],
        k: Intrinsics,
        weights: Weights,
        max_depth: f64,
    ) -> Result<AnchoredFuser, FusionError> {
        if template.len() != domain.template_vertex_count {
            return Err(FusionError::InvalidOption {
                name: "template",
                value: format!("{} vertices", template.len()),
                reason: "must match the face domain's template",
            });
        }
        k.validate()?;
        let n = domain.vertex_count();
        let mut rest = vec![[0.0; 3]; n];
        domain.interpolate(template, &mut rest);
        let points: Vec<[f64; 3]> = rest
            .iter()
            .map(|p| p.map(|c| c * DOMAIN_UNITS_PER_METRE))
            .collect();
        let l = cotan_laplacian(&points, &domain.triangles)?;
        let m_lumped = lumped_mass(&points, &domain.triangles)?;
        let mass = mass_matrix(&points, &domain.triangles)?;
        let ops = Operators {
            data_mass: mass.clone(),
            mass,
            biharmonic: biharmonic(&l, &m_lumped)?,
        };
        let rest = Mat::from_fn(n, 3, |i, c| rest[i][c]);
        let system = FusionSystem::new(ops, weights)?;
        Ok(AnchoredFuser {
            metrics: SurfaceMetrics::new(n, &domain.triangles, &domain.boundary),
            domain,
            k,
            max_depth,
            solver: StreamingSolver::new(system),
            offset: Mat::zeros(n, 3),
            frame_template: vec![[0.0; 3]; n],
            rest,
            pixels: vec![[0.0; 2]; n],
            raw: vec![[0.0; 3]; n],
            valid: vec![false; n],
            data: Mat::zeros(n, 3),
            b: Mat::zeros(n, 3),
            deviation: Mat::zeros(n, 3),
            solution: vec![[0.0; 3]; n],
            pose: RigidTransform::IDENTITY,
            scale: 1.0,
            scale_filter: ConstantVelocity::new(SCALE_FILTER_RATIO),
            ratios: Vec::with_capacity(n),
        })
    }

    pub fn domain(&self) -> &FaceDomain {
        &self.domain
    }

    pub fn intrinsics(&self) -> &Intrinsics {
        &self.k
    }

    pub fn solver(&self) -> &StreamingSolver {
        &self.solver
    }

    pub fn solver_mut(&mut self) -> &mut StreamingSolver {
        &mut self.solver
    }

    /// The face's size relative to the template, as measured by the depth maps so far (1 with
    /// the face CNN's surface, which has the template's size by construction).
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Measures the face's scale in this frame — the median over valid vertices of the ratio
    /// of the depth map's ray distance to the posed frame template's — and filters it
    /// ([`SCALE_FILTER_RATIO`]).
    fn update_scale(&mut self, pose: &RigidTransform) {
        self.ratios.clear();
        for i in (0..self.domain.vertex_count()).filter(|&i| self.valid[i]) {
            let t = pose.apply(self.frame_template[i]);
            self.ratios.push(norm(self.raw[i]) / norm(t));
        }
        if self.ratios.is_empty() {
            return;
        }
        let mid = self.ratios.len() / 2;
        let (_, &mut median, _) = self.ratios.select_nth_unstable_by(mid, f64::total_cmp);
        // The first measurement after a reset is taken as it is.
        self.scale = self.scale_filter.step(&[median], SCALE_FRAME_INTERVAL_S)[0];
    }

    /// Per vertex: whether the last frame had a raw sample there.
    pub fn valid(&self) -> &[bool] {
        &self.valid
    }

    /// The last frame's vertex pixel positions.
    pub fn pixels(&self) -> &[[f64; 2]] {
        &self.pixels
    }

    /// The last frame's head pose at the face's scale (the given pose with its translation
    /// multiplied by [`AnchoredFuser::scale`]).
    pub fn pose(&self) -> &RigidTransform {
        &self.pose
    }

    /// The last frame's template posed in the camera at the face's scale (`T_k s C_k`, #V):
    /// the template alone, e.g. the fitted model with the depth used only for its scale.
    pub fn posed_template(&self) -> impl ExactSizeIterator<Item = [f64; 3]> + '_ {
        (0..self.offset.nrows()).map(|i| {
            self.pose.apply([
                self.offset[(i, 0)],
                self.offset[(i, 1)],
                self.offset[(i, 2)],
            ])
        })
    }

    /// Fuses one frame.
    ///
    /// # Errors
    /// When the frame's landmarks, surface or template do not have one entry per template
    /// vertex, or the pose is not finite.
    pub fn process(&mut self, frame: &AnchoredFrame<'_>) -> Result<FusedFrame, FusionError> {
        let start = Instant::now();
        let m = self.domain.template_vertex_count;
        let wrong = |what: &'static str, found: usize| FusionError::InvalidOption {
            name: what,
            value: format!("{found} entries"),
            reason: "needs one per template vertex",
        };
        if frame.landmarks_px.len() != m {
            return Err(wrong("landmarks", frame.landmarks_px.len()));
        }
        if let FrameDepth::Surface(s) = frame.depth {
            if s.len() != m {
                return Err(wrong("surface", s.len()));
            }
        }
        if let Some(t) = frame.template {
            if t.len() != m {
                return Err(wrong("template", t.len()));
            }
        }
        if !frame.pose.is_finite() {
            return Err(FusionError::InvalidOption {
                name: "pose",
                value: format!("{:?}", frame.pose),
                reason: "must be finite",
            });
        }
        self.domain
            .interpolate(frame.landmarks_px, &mut self.pixels);
        match frame.template {
            Some(t) => self.domain.interpolate(t, &mut self.frame_template),
            None => {
                for (i, p) in self.frame_template.iter_mut().enumerate() {
                    *p = [self.rest[(i, 0)], self.rest[(i, 1)], self.rest[(i, 2)]];
                }
            }
        }
        let mut valid_count = 0usize;
        for i in 0..self.domain.vertex_count() {
            let sample = match frame.depth {
                FrameDepth::Surface(points) => self.surface_sample(i, points),
                FrameDepth::Map(depth) => {
                    let [u, v] = self.pixels[i];
                    depth
                        .sample_ray_distance(&self.k, u, v)
                        .filter(|&d| d > 0.0 && d <= self.max_depth)
                        .map(|d| self.k.backproject(u, v, d))
                }
            };
            self.valid[i] = sample.is_some();
            if let Some(x) = sample {
                valid_count += 1;
                self.raw[i] = x;
            }
        }
        if let FrameDepth::Map(_) = frame.depth {
            self.update_scale(&frame.pose);
        }
        // The fitted pose at the face's scale: the template scaled about the camera centre
        // projects exactly as the fitted one.
        let pose = RigidTransform {
            translation: frame.pose.translation.map(|t| t * self.scale),
            ..frame.pose
        };
        self.pose = pose;
        let previous = self.solver.previous();
        for i in 0..self.domain.vertex_count() {
            let offset = self.frame_template[i].map(|c| c * self.scale);
            // A hole keeps the previous deviation from the template (the surface carried by
            // the head and the template's motion), else the template.
            let deviation = if self.valid[i] {
                let head = pose.apply_inverse(self.raw[i]);
                std::array::from_fn(|c| head[c] - offset[c])
            } else {
                let d = previous.map_or([0.0; 3], |p| [p[(i, 0)], p[(i, 1)], p[(i, 2)]]);
                self.raw[i] = pose.apply(std::array::from_fn(|c| offset[c] + d[c]));
                d
            };
            for c in 0..3 {
                self.data[(i, c)] = deviation[c];
                self.offset[(i, c)] = offset[c];
            }
        }
        let n = self.domain.vertex_count();
        let mut result = FusedFrame {
            valid_fraction: valid_count as f64 / n as f64,
            ..FusedFrame::unsolved(FrameStatus::Solved)
        };
        if valid_count == 0 {
            let Some(prev) = self.solver.previous() else {
                result.status = FrameStatus::NoData;
                return Ok(result);
            };
            self.deviation.copy_from(prev);
            self.write_solution();
            result.status = FrameStatus::Carried;
            return Ok(result);
        }
        self.solver
            .system()
            .apply_mass(self.data.as_ref(), 1.0, 0.0, self.b.as_mut());
        result.rhs_seconds = start.elapsed().as_secs_f64();
        let solve = Instant::now();
        let report = self.solver.step(self.b.as_ref(), self.deviation.as_mut());
        result.solve_seconds = solve.elapsed().as_secs_f64();
        result.relative_residual = report.relative_residual;
        self.write_solution();
        Ok(result)
    }

    /// Makes a clip-solved frame's state (see [`AnchoredFuser::clip_state`]) the current
    /// solution and maps it to camera coordinates.
    pub fn load_clip_state(&mut self, state: &ClipState) {
        self.deviation.copy_from(&state.x);
        self.offset.copy_from(&state.offset);
        self.pose = state.pose;
        self.write_solution();
    }

    fn write_solution(&mut self) {
        for (i, s) in self.solution.iter_mut().enumerate() {
            *s = self.pose.apply(std::array::from_fn(|c| {
                self.deviation[(i, c)] + self.offset[(i, c)]
            }));
        }
    }

    /// The point of the surface `points` seen at vertex i's pixel: on the plane of its
    /// template triangle, perspective-correct barycentrics `β_j ∝ b_j / z_j`.
    fn surface_sample(&self, i: usize, points: &[[f64; 3]]) -> Option<[f64; 3]> {
        let a = self.domain.anchors[i];
        let t = self.domain.template_triangles[a.triangle as usize];
        let corners = t.map(|j| points[j as usize]);
        if corners
            .iter()
            .any(|p| !(p[2] > 0.0 && p.iter().all(|c| c.is_finite())))
        {
            return None;
        }
        let w: [f64; 3] = std::array::from_fn(|j| a.bary[j] / corners[j][2]);
        let sum: f64 = w.iter().sum();
        let x: [f64; 3] =
            std::array::from_fn(|c| (0..3).map(|j| w[j] * corners[j][c]).sum::<f64>() / sum);
        (x[2] <= self.max_depth).then_some(x)
    }
}

impl SurfaceFuser for AnchoredFuser {
    fn triangles(&self) -> &[[u32; 3]] {
        &self.domain.triangles
    }

    /// Camera coordinates.
    fn solution(&self) -> &[[f64; 3]] {
        &self.solution
    }

    /// Camera coordinates; holes hold what the solver used instead (see
    /// [`AnchoredFuser::valid`]).
    fn raw(&self) -> &[[f64; 3]] {
        &self.raw
    }

    /// Also forgets the face's measured scale.
    fn reset(&mut self) {
        self.solver.reset();
        self.scale = 1.0;
        self.scale_filter.reset();
    }

    fn frame_quality(&mut self) -> (SurfaceQuality, SurfaceQuality) {
        (
            self.metrics.evaluate(&self.raw),
            self.metrics.evaluate(&self.solution),
        )
    }

    /// Head coordinates; the pose is the head pose at the face's scale.
    fn clip_state(&self) -> ClipState {
        ClipState {
            b: self.b.clone(),
            x: self.deviation.clone(),
            pose: self.pose,
            offset: self.offset.clone(),
        }
    }

    fn system_mut(&mut self) -> &mut FusionSystem {
        self.solver.system_mut()
    }

    fn load_clip_solution(&mut self, state: &ClipState, raw: &[[f64; 3]]) {
        self.load_clip_state(state);
        self.raw.copy_from_slice(raw);
    }
}
