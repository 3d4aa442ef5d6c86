//! The morphable-model fit to tracked landmarks (paper Eqs. 3.2–3.3 as corrected by ERRATA 7):
//! per frame, alternate the rigid head pose — from the landmarks that expressions barely move,
//! so blinks and mouth motion do not move the head — with the linear ridge solve
//! `(AᵀWA + αI) p = AᵀW(ℓ − P S̄)` for the shape, where A is the model basis at the landmarks
//! projected through the camera's Jacobian at the current estimate (perspective with the known
//! intrinsics, not scaled orthographic).
//!
//! - **Identity** `p` is one vector for the whole clip: every frame adds the information its
//!   landmarks carry about p — its normal equations with the frame's expression integrated out
//!   (a Schur complement, see `solve_identity`) — to a running sum, and p is solved from that
//!   sum: it settles as frames accumulate, does not follow expressions, and takes the shape the
//!   face keeps in every frame (which each frame's expression would otherwise pay for).
//! - **Expression** `e` is per frame and bounded to [0, 1] by a box-constrained solve
//!   ([`super::bounded_least_squares`]), warm-started from the previous frame.
//! - **Weights**: landmark residuals are divided by their noise σ, in pixels of the landmark
//!   network's 192-pixel crop scaled to the frame by the face's size, so W does not depend on
//!   the resolution; the priors then read in the modes' own units: identity weights ~ N(0, 1)
//!   (α = 1), expression weights with a prior standard deviation [`FitOptions::expression_prior`].
//!   The face outline's side landmarks are silhouette points: they slide to the model vertex
//!   nearest them each frame ([`super::Contour`]) and count with
//!   [`FitOptions::outline_weight`]. The lower face's landmarks are no evidence for the upper
//!   face's shapes ([`super::region_evidence`]).
//! - **Cost**: each alternation is a Gauss–Newton step with the exact perspective gradient
//!   `AᵀW(ℓ − π)`; the normal matrix `AᵀWA` (the 7 million multiply-adds of a frame) is
//!   formed once per frame, in single precision, at the frame's first linearisation and reused
//!   by its later alternations — the fixed point is still the exact optimum, as only the step's
//!   metric is approximate. (An affine camera's normal matrix, cheaper still, misses the
//!   curvature of depth-wise modes and made the steps overshoot.)

use faer::linalg::matmul::matmul;
use faer::linalg::solvers::Solve;
use faer::{Accum, Mat, Par};
use visage_camera::{Intrinsics, RigidTransform};

use super::bounded_least_squares::BoxQp;
use super::contour::Contour;
use super::landmark_basis::{dot, LandmarkBasis};
use super::perspective::project_with_jacobian;
use super::region_evidence::keep_evidence_local;
use super::rigid_pose::{refine_pose, translation_for_rotation};
use super::view_correction::{centroid, view_of, ViewCorrection};
use crate::FaceModel;

/// FaceMesh's face-outline landmarks (MediaPipe's `FACEMESH_FACE_OVAL`).
pub const FACE_OVAL: [usize; 36] = [
    10, 338, 297, 332, 284, 251, 389, 356, 454, 323, 361, 288, 397, 365, 379, 378, 400, 377, 152,
    148, 176, 149, 150, 136, 172, 58, 132, 93, 234, 127, 162, 21, 54, 103, 67, 109,
];

/// Gauss–Newton steps of the rigid fit on the uncorrected landmarks whose view the
/// [`ViewCorrection`] is read at (from the previous frame's pose: converged).
pub const VIEW_POSE_ITERATIONS: usize = 3;

/// The prior weight of an expression held at 0 (out of the landmark fit).
const HELD: f64 = 1e9;

/// The landmark network's input size (pixels): landmark noise is stated in its units.
const CROP_PX: f64 = 192.0;

/// MediaPipe's crop is this many times the face's extent.
const CROP_SCALE: f64 = 1.5;

/// The model frame (x right, y up, the face looking along +z) seen frontally by the camera
/// (x right, y down, z forward): a half turn about x.
pub const FRONTAL: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]];

/// Options of the fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitOptions {
    /// Landmark noise σ in pixels of the landmark network's 192-pixel crop.
    pub landmark_noise_crop_px: f64,
    /// Prior standard deviation of an identity weight (the modes are N(0, 1): 1).
    pub identity_prior: f64,
    /// Prior standard deviation of an expression weight (the weights live in [0, 1]).
    pub expression_prior: f64,
    /// Relative weight of the face-outline landmarks ([`FACE_OVAL`]).
    pub outline_weight: f64,
    /// A landmark counts for the head pose when no expression moves it by more than this
    /// (metres).
    pub rigid_motion_m: f64,
    /// Expressions left out of the landmark fit (held at 0): the eye-look shapes, which the
    /// landmarks see only through the lids — gaze comes from the irises instead.
    pub gaze_from_landmarks: bool,
    /// Take the landmark network's bias that follows the view off the landmarks before the
    /// fit ([`ViewCorrection::embedded`], read at the view of a rigid fit of the uncorrected
    /// landmarks).
    pub view_correction: bool,
    /// The landmark noise grows with the view: σ · (1 + (yaw / v)² + (pitch / v)²) with the
    /// view's yaw and pitch and v this many degrees (`None`: the same at every view). What the
    /// view correction leaves of the landmarks' bias grows as the head turns — the rigid turn's
    /// leak sits at more than 30° of yaw — so a turned face's landmarks say less about its
    /// expression. On the pixel benchmark 20° took the rigid leak's p99 from 0.32 to 0.26 (30°:
    /// 0.30) and the tuning take's MAE from 0.118 to 0.110.
    pub landmark_noise_view_deg: Option<f64>,
    /// The lower face's landmarks are no evidence for the upper face's shapes
    /// ([`super::region_evidence`]): speech does not open a sneer or a squint.
    pub region_evidence: bool,
    /// Pose / shape alternations per frame.
    pub iterations: usize,
    /// Gauss–Newton steps of the pose per alternation.
    pub pose_iterations: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            landmark_noise_crop_px: 1.0,
            identity_prior: 1.0,
            expression_prior: 0.5,
            outline_weight: 1.0,
            rigid_motion_m: 0.004,
            gaze_from_landmarks: false,
            view_correction: true,
            landmark_noise_view_deg: Some(20.0),
            region_evidence: true,
            iterations: 2,
            pose_iterations: 2,
        }
    }
}

impl FitOptions {
    /// The defaults for landmarks that are the model's own projections (synthetic ones, plus
    /// noise): without the corrections for MediaPipe's network — its bias that follows the view
    /// and its noise that grows with it — and with every landmark the evidence of every shape,
    /// as the model that made them.
    pub fn exact_landmarks() -> Self {
        FitOptions {
            view_correction: false,
            landmark_noise_view_deg: None,
            region_evidence: false,
            ..FitOptions::default()
        }
    }
}

/// One frame's fit.
#[derive(Clone, Debug, PartialEq)]
pub struct FaceFit {
    /// Model frame → camera, metres.
    pub pose: RigidTransform,
    /// Expression weights in [0, 1], in the model's expression order.
    pub expression: Vec<f64>,
    /// The identity estimate after this frame.
    pub identity: Vec<f64>,
    /// Mean distance (px) between the fitted landmarks' projections and the tracked ones.
    pub mean_error_px: f64,
}

/// The fit's state over a clip and its scratch buffers (allocated once).
pub struct FaceFitter {
    basis: LandmarkBasis,
    contour: Contour,
    options: FitOptions,
    /// Per landmark: relative weight in the shape solve and in the pose.
    shape_weight: Vec<f64>,
    /// Per expression: the prior's weight `1 / σ²` (a shape held at 0 gets [`HELD`]).
    expression_alpha: Vec<f64>,
    rigid_weight: Vec<f64>,
    view_correction: Option<ViewCorrection>,
    /// The landmarks with the view's bias taken off, scratch.
    corrected: Vec<[f64; 2]>,
    pose: Option<RigidTransform>,
    identity: Vec<f64>,
    expression: Vec<f64>,
    /// Σ over past frames of their identity equations `H p = b`.
    identity_information: Mat<f64>,
    identity_rhs: Vec<f64>,
    frames: usize,
    // Scratch.
    points: Vec<[f64; 3]>,
    /// `N`, #modes × #modes, row-major.
    normal: Vec<f64>,
    /// `Aᵀ` and `(WA)ᵀ` (#modes × 2·#landmarks) and `N` in single precision.
    at: Mat<f32>,
    wat: Mat<f32>,
    normal32: Mat<f32>,
    gradient: Vec<f64>,
    q: Mat<f64>,
    c: Vec<f64>,
    h: Mat<f64>,
    b: Mat<f64>,
    frame_rhs: Vec<f64>,
    frame_information: Mat<f64>,
    absolute_rhs: Vec<f64>,
    s: Mat<f64>,
    coupling: Mat<f64>,
    /// p and e at the current linearisation.
    previous_identity: Vec<f64>,
    previous_expression: Vec<f64>,
    /// `[p; e]`, scratch.
    state: Vec<f64>,
    /// Whether `points` hold the landmarks of the current identity and expression.
    points_current: bool,
    /// `p − p⁰`, scratch.
    delta: Vec<f64>,
    qp: BoxQp,
}

impl FaceFitter {
    /// A fitter for `model`'s landmarks.
    pub fn new(model: &FaceModel, options: FitOptions) -> FaceFitter {
        let mut basis = LandmarkBasis::new(model);
        let contour = Contour::new(model, &basis);
        let n = basis.landmark_count();
        let (n_id, n_ex) = (basis.identity_count, basis.expression_count);
        let m = n_id + n_ex;
        let mut shape_weight = vec![1.0; n];
        for &j in FACE_OVAL.iter().filter(|&&j| j < n) {
            shape_weight[j] = options.outline_weight;
        }
        let rigid_weight = (0..n)
            .map(|j| {
                let rigid = basis.expression_motion(j) <= options.rigid_motion_m;
                if rigid && !FACE_OVAL.contains(&j) {
                    1.0
                } else {
                    0.0
                }
            })
            .collect();
        // After the rigid landmarks: a lip an upper shape moves is not rigid.
        if options.region_evidence {
            keep_evidence_local(&mut basis, &model.expression_names);
        }
        let free = 1.0 / (options.expression_prior * options.expression_prior);
        let expression_alpha = model
            .expression_names
            .iter()
            .map(|name| {
                if !options.gaze_from_landmarks && name.starts_with("eyeLook") {
                    HELD
                } else {
                    free
                }
            })
            .collect();
        FaceFitter {
            options,
            shape_weight,
            expression_alpha,
            rigid_weight,
            view_correction: options.view_correction.then(ViewCorrection::embedded),
            corrected: Vec::with_capacity(n),
            pose: None,
            identity: vec![0.0; n_id],
            expression: vec![0.0; n_ex],
            identity_information: Mat::zeros(n_id, n_id),
            identity_rhs: vec![0.0; n_id],
            frames: 0,
            points: vec![[0.0; 3]; n],
            normal: vec![0.0; m * m],
            at: Mat::zeros(m, 2 * n),
            wat: Mat::zeros(m, 2 * n),
            normal32: Mat::zeros(m, m),
            gradient: vec![0.0; m],
            q: Mat::zeros(n_ex, n_ex),
            c: vec![0.0; n_ex],
            h: Mat::zeros(n_id, n_id),
            b: Mat::zeros(n_id, 1),
            frame_rhs: vec![0.0; n_id],
            frame_information: Mat::zeros(n_id, n_id),
            absolute_rhs: vec![0.0; m],
            s: Mat::zeros(n_ex, n_ex),
            coupling: Mat::zeros(n_ex, n_id + 1),
            previous_identity: vec![0.0; n_id],
            previous_expression: vec![0.0; n_ex],
            state: Vec::with_capacity(m),
            points_current: false,
            delta: vec![0.0; n_id],
            qp: BoxQp::new(n_ex),
            basis,
            contour,
        }
    }

    /// The last fit's landmarks in the model frame (metres).
    pub fn landmark_points(&self) -> &[[f64; 3]] {
        &self.points
    }

    /// The last fit's landmarks projected into the frame (pixels), into `out`.
    pub fn projected_landmarks(&self, k: &Intrinsics, out: &mut Vec<[f64; 2]>) {
        out.clear();
        if let Some(pose) = &self.pose {
            out.extend(self.points.iter().map(|p| k.project(pose.apply(*p))));
        }
    }

    /// The landmarks that count for the head pose.
    pub fn rigid_landmarks(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.rigid_weight.len()).filter(|&j| self.rigid_weight[j] > 0.0)
    }

    /// The current identity estimate.
    pub fn identity(&self) -> &[f64] {
        &self.identity
    }

    /// Frames whose information the identity holds.
    pub fn identity_frames(&self) -> usize {
        self.frames
    }

    /// Forgets the head pose and the expression (the face was lost); the identity stays.
    pub fn lose_track(&mut self) {
        self.pose = None;
        self.expression.iter_mut().for_each(|e| *e = 0.0);
        self.points_current = false;
    }

    /// Forgets everything, identity included (another person).
    pub fn reset(&mut self) {
        self.lose_track();
        self.identity.iter_mut().for_each(|p| *p = 0.0);
        self.identity_information.fill(0.0);
        self.identity_rhs.iter_mut().for_each(|b| *b = 0.0);
        self.frames = 0;
    }

    /// Fits one frame: `landmarks_px` are the tracked landmarks (frame pixels, one per model
    /// landmark), `rotation` a starting head rotation (model frame → camera) for a frame
    /// without a previous fit — e.g. from a rigid fit of the landmarks — else [`FRONTAL`].
    ///
    /// # Panics
    /// If `landmarks_px` does not have one entry per model landmark.
    #[track_caller]
    pub fn fit(
        &mut self,
        k: &Intrinsics,
        landmarks_px: &[[f64; 2]],
        rotation: Option<[[f64; 3]; 3]>,
    ) -> FaceFit {
        let n = self.basis.landmark_count();
        assert_eq!(landmarks_px.len(), n, "one pixel per model landmark");
        let sigma = self.noise_px(landmarks_px);
        if !self.points_current {
            self.basis
                .landmarks(&self.identity, &self.expression, &mut self.points);
        }
        let mut pose = match self.pose {
            Some(p) => p,
            None => {
                let r = rotation.unwrap_or(FRONTAL);
                let t =
                    translation_for_rotation(k, &r, &self.points, landmarks_px, &self.rigid_weight)
                        .unwrap_or([0.0, 0.0, 0.6]);
                RigidTransform {
                    rotation: r,
                    translation: t,
                }
            }
        };
        if self.view_correction.is_some() {
            // The view the table is read at: a rigid fit of the uncorrected landmarks.
            refine_pose(
                k,
                &mut pose,
                &self.points,
                landmarks_px,
                &self.rigid_weight,
                VIEW_POSE_ITERATIONS,
            );
        }
        let view = view_of(&pose, centroid(&self.points));
        let mut corrected = std::mem::take(&mut self.corrected);
        let landmarks_px = match &self.view_correction {
            Some(table) => {
                table.correct(k, &pose, view, &self.points, landmarks_px, &mut corrected);
                &corrected[..]
            }
            None => landmarks_px,
        };
        let sigma = match self.options.landmark_noise_view_deg {
            Some(v) => {
                let [yaw, pitch] = view.map(f64::to_degrees);
                sigma * (1.0 + (yaw / v).powi(2) + (pitch / v).powi(2))
            }
            None => sigma,
        };
        for iteration in 0..self.options.iterations {
            if iteration > 0 {
                self.basis
                    .landmarks(&self.identity, &self.expression, &mut self.points);
            }
            refine_pose(
                k,
                &mut pose,
                &self.points,
                landmarks_px,
                &self.rigid_weight,
                self.options.pose_iterations,
            );
            if iteration == 0 {
                self.state.clear();
                self.state.extend_from_slice(&self.identity);
                self.state.extend_from_slice(&self.expression);
                self.contour
                    .slide(k, &pose, &self.state, landmarks_px, &mut self.basis);
                for j in self.contour.landmarks() {
                    self.points[j] = self.basis.landmark(j, &self.identity, &self.expression);
                }
            }
            self.linearise(k, &pose, landmarks_px, sigma, iteration == 0);
            self.previous_identity.copy_from_slice(&self.identity);
            self.previous_expression.copy_from_slice(&self.expression);
            self.solve_identity(iteration + 1 == self.options.iterations);
            self.solve_expression();
        }
        self.frames += 1;
        self.pose = Some(pose);
        self.basis
            .landmarks(&self.identity, &self.expression, &mut self.points);
        self.points_current = true;
        let mean_error_px = self
            .points
            .iter()
            .zip(landmarks_px)
            .map(|(p, l)| {
                let u = k.project(pose.apply(*p));
                (u[0] - l[0]).hypot(u[1] - l[1])
            })
            .sum::<f64>()
            / n as f64;
        self.corrected = corrected;
        FaceFit {
            pose,
            expression: self.expression.clone(),
            identity: self.identity.clone(),
            mean_error_px,
        }
    }

    /// Landmark noise in frame pixels: the crop noise scaled by the crop's size, which
    /// MediaPipe makes 1.5 × the face's extent.
    fn noise_px(&self, landmarks_px: &[[f64; 2]]) -> f64 {
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        for l in landmarks_px {
            for c in 0..2 {
                lo[c] = lo[c].min(l[c]);
                hi[c] = hi[c].max(l[c]);
            }
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1.0);
        self.options.landmark_noise_crop_px * CROP_SCALE * extent / CROP_PX
    }

    /// The Gauss–Newton model at `pose` and the current shape `x⁰ = [p; e]`: the exact
    /// gradient `g = AᵀW(ℓ − π(R L_j(x⁰) + t))` and, with `form_normal`, `N = AᵀWA`,
    /// W = shape weights / σ².
    fn linearise(
        &mut self,
        k: &Intrinsics,
        pose: &RigidTransform,
        landmarks_px: &[[f64; 2]],
        sigma: f64,
        form_normal: bool,
    ) {
        let m = self.gradient.len();
        let inv_var = 1.0 / (sigma * sigma);
        self.gradient.iter_mut().for_each(|g| *g = 0.0);
        for (j, l) in landmarks_px.iter().enumerate() {
            let y = pose.apply(self.points[j]);
            let (u, jac) = project_with_jacobian(k, y);
            let w = self.shape_weight[j] * inv_var;
            // P = J R (2 × 3): the image motion of landmark j per model-frame displacement.
            let p: [[f64; 3]; 2] = std::array::from_fn(|r| {
                std::array::from_fn(|c| (0..3).map(|i| jac[r][i] * pose.rotation[i][c]).sum())
            });
            // q = Pᵀ w (ℓ − u).
            let res = [w * (l[0] - u[0]), w * (l[1] - u[1])];
            let q: [f64; 3] = std::array::from_fn(|c| p[0][c] * res[0] + p[1][c] * res[1]);
            let rows = [
                self.basis.row(3 * j),
                self.basis.row(3 * j + 1),
                self.basis.row(3 * j + 2),
            ];
            for (c, row) in rows.iter().enumerate() {
                for (g, &a) in self.gradient.iter_mut().zip(*row) {
                    *g += a * q[c];
                }
            }
            if form_normal {
                // Columns of Aᵀ are contiguous (column-major), one per landmark coordinate.
                for (r, pr) in p.iter().enumerate() {
                    let col = 2 * j + r;
                    let coordinates = rows[0].iter().zip(rows[1]).zip(rows[2]);
                    for (i, ((x, y), z)) in coordinates.enumerate() {
                        let a = (pr[0] * x + pr[1] * y + pr[2] * z) as f32;
                        self.at[(i, col)] = a;
                        self.wat[(i, col)] = w as f32 * a;
                    }
                }
            }
        }
        if form_normal {
            matmul(
                self.normal32.as_mut(),
                Accum::Replace,
                self.at.as_ref(),
                self.wat.transpose(),
                1.0,
                Par::Seq,
            );
            for r in 0..m {
                for c in 0..m {
                    self.normal[r * m + c] = self.normal32[(r, c)] as f64;
                }
            }
        }
    }

    /// The expression step at the new identity p: `e = argmin ½ (e − e⁰)ᵀ N_ee (e − e⁰)
    /// + (e − e⁰)ᵀ N_ep (p − p⁰) − g_eᵀ(e − e⁰) + ½ α_e ‖e‖²` over [0, 1]^#e,
    /// `α_e = 1 / expression_prior²`.
    fn solve_expression(&mut self) {
        let (n_id, n_ex) = (self.basis.identity_count, self.basis.expression_count);
        let m = n_id + n_ex;
        for (d, (p, p0)) in self
            .delta
            .iter_mut()
            .zip(self.identity.iter().zip(&self.previous_identity))
        {
            *d = p - p0;
        }
        for i in 0..n_ex {
            let row = &self.normal[(n_id + i) * m..(n_id + i + 1) * m];
            let (ep, ee) = row.split_at(n_id);
            for (j, &v) in ee.iter().enumerate() {
                self.q[(i, j)] = v;
            }
            self.c[i] =
                self.gradient[n_id + i] + dot(ee, &self.previous_expression) - dot(ep, &self.delta);
            self.q[(i, i)] += self.expression_alpha[i];
        }
        self.qp
            .solve(self.q.as_ref(), &self.c, 0.0, 1.0, &mut self.expression);
    }

    /// The identity step, with the frame's expression marginalised: the frame's data term is
    /// the quadratic `½ xᵀNx − ĝᵀx` in `x = [p; e]` (`ĝ = g + N x⁰`); with e's Gaussian prior
    /// `½ α_e ‖e‖²` integrated out, what it says about p is `H_k = N_pp − N_pe S⁻¹ N_ep`,
    /// `b_k = ĝ_p − N_pe S⁻¹ ĝ_e`, `S = N_ee + α_e I`. Summed over the clip with the N(0, 1)
    /// prior this is the joint MAP identity: a shape the face keeps in every frame goes to p,
    /// which pays for it once, rather than to each frame's expression (the box [0, 1] on e is
    /// left out of the marginal). With `commit`, the frame's `(H_k, b_k)` join the sum.
    fn solve_identity(&mut self, commit: bool) {
        let (n_id, n_ex) = (self.basis.identity_count, self.basis.expression_count);
        let m = n_id + n_ex;
        if n_id == 0 {
            return;
        }
        // ĝ = g + N x⁰ with x⁰ the linearisation point.
        self.state.clear();
        self.state.extend_from_slice(&self.previous_identity);
        self.state.extend_from_slice(&self.previous_expression);
        for i in 0..m {
            self.absolute_rhs[i] =
                self.gradient[i] + dot(&self.normal[i * m..(i + 1) * m], &self.state);
        }
        // S and [N_ep | ĝ_e].
        for i in 0..n_ex {
            for j in 0..n_ex {
                self.s[(i, j)] = self.normal[(n_id + i) * m + n_id + j];
            }
            self.s[(i, i)] += self.expression_alpha[i];
            for j in 0..n_id {
                self.coupling[(i, j)] = self.normal[(n_id + i) * m + j];
            }
            self.coupling[(i, n_id)] = self.absolute_rhs[n_id + i];
        }
        let Ok(llt) = self.s.llt(faer::Side::Lower) else {
            return;
        };
        let solved = llt.solve(&self.coupling);
        for i in 0..n_id {
            let row = &self.normal[i * m..(i + 1) * m];
            let (pp, pe) = row.split_at(n_id);
            let schur = |j: usize| -> f64 {
                let column = solved.col(j);
                match column.try_as_col_major() {
                    Some(c) => dot(pe, c.as_slice()),
                    None => (0..n_ex).map(|k| pe[k] * column[k]).sum(),
                }
            };
            for (j, &v) in pp.iter().enumerate() {
                self.frame_information[(i, j)] = v - schur(j);
            }
            self.frame_rhs[i] = self.absolute_rhs[i] - schur(n_id);
        }
        for i in 0..n_id {
            for j in 0..n_id {
                let v = 0.5 * (self.frame_information[(i, j)] + self.frame_information[(j, i)]);
                self.h[(i, j)] = self.identity_information[(i, j)] + v;
            }
            self.h[(i, i)] += 1.0 / (self.options.identity_prior * self.options.identity_prior);
            self.b[(i, 0)] = self.identity_rhs[i] + self.frame_rhs[i];
        }
        if commit {
            for i in 0..n_id {
                for j in 0..n_id {
                    self.identity_information[(i, j)] += self.frame_information[(i, j)];
                }
                self.identity_rhs[i] += self.frame_rhs[i];
            }
        }
        if let Ok(llt) = self.h.llt(faer::Side::Lower) {
            let x = llt.solve(&self.b);
            for i in 0..n_id {
                self.identity[i] = x[(i, 0)];
            }
        }
    }
}
