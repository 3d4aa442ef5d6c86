//! The methods compared by the benchmark. Each is a function of the same
//! input — the noisy depth sequence, the camera, the sequence's meshing domain and, for the
//! face-anchored methods, the simulated tracker's landmarks and poses — and returns
//! one vertex field per frame (#V × 3, metres, camera coordinates) on its [`VertexKind`]: the
//! image-plane mesh shared by the paper's methods, or the face-anchored mesh. Adding a method
//! is a variant here and a line in [`Method::run`].

use std::time::Instant;

use faer::Mat;
use visage_camera::{DepthMap, Intrinsics};
use visage_fem::{solve_clip, ClipOptions, FusionSystem, Weights};
use visage_fusion::{
    AnchoredFrame, AnchoredFuser, ClipState, FaceDomain, FrameDepth, FrameStatus, FusionSetup,
    ImagePlaneFuser, MeshingOptions, SurfaceFuser,
};
use visage_mesh::Mask;
use visage_morphable::{FaceFitter, FaceModel, FitOptions};

use crate::sift_fairing::{
    control_order, keypoint_weights, random_control_weights, FairingKeypoints,
};
use crate::simulated_tracker::TrackedSequence;
use crate::taubin::taubin_smooth;
use crate::vertex_filter::VertexFilter;
use crate::EvalError;

/// A reconstruction method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// The depth at each vertex back-projected (`D(x_i) ρ(x_i)`), holes in-painted by diffusion
    /// from the valid vertices (`FusionSetup::inpaint`).
    Raw,
    /// The paper's regulariser frame by frame without the temporal term (μ = 0).
    PerFrameBiharmonic,
    /// The paper's streaming fusion (ERRATA 4): `(M_D + λK + μM) s^k = b^k + μ M s^{k−1}`.
    Streaming,
    /// [`Method::Streaming`] on the image-plane mesh with the SIFT keypoints of the first
    /// frame's colour render (or every k-th frame's; constant or textured albedo,
    /// [`crate::SiftAnchorOptions`]) added as vertices ([`MethodInput::sift_anchors`], paper §3's
    /// "semantic anchors"). An experiment: scored only when asked for by name
    /// ([`crate::OPT_IN_METHODS`]).
    StreamingSiftAnchors,
    /// The exact whole-clip minimiser (ERRATA 1, 4, 5), PCG from the streaming solutions.
    Clip,
    /// [`Method::Raw`] followed by Taubin λ|μ smoothing with this many iterations.
    Taubin { iterations: usize },
    /// The face-anchored, pose-compensated streaming fusion
    /// ([`visage_fusion::AnchoredFuser`]) on the depth sampled at the tracked vertices.
    FaceAnchored,
    /// Its whole-clip minimiser: [`visage_fem::solve_clip`] on the head-coordinate right-hand
    /// sides of the frames, from the streaming solutions.
    FaceAnchoredClip,
    /// [`Method::FaceAnchored`] then fairing (paper §5, [`visage_fem::fair`]) of every frame
    /// with a smoothing length of [`BENCHMARK_FAIRING_LENGTH_M`], the system measured on the
    /// first frame and factored once, as `visage run --fair`.
    FaceAnchoredFaired,
    /// [`Method::FaceAnchoredFaired`] with per-frame fairing weights from the SIFT keypoints of
    /// that frame's colour render ([`MethodInput::fairing_keypoints`],
    /// [`crate::keypoint_weights`]): full weight at vertices projecting near a keypoint, a
    /// lower base weight elsewhere, so the fairing smooths more where the image shows no
    /// detail (paper §3's keypoints as weighted constraints). The system is built and factored
    /// every frame (the weights change; its time per frame counts the factorisation), its
    /// operators measured on the first frame as the uniform method's. An experiment: scored
    /// only when asked for by name ([`crate::OPT_IN_METHODS`]).
    FaceAnchoredFairedSift,
    /// The morphable model fitted to the tracked landmarks ([`visage_morphable::FaceFitter`]:
    /// pose, the clip's identity, the frame's expression), placed at the face's scale measured
    /// from the depth maps — the depth used for nothing else. Landmarks alone cannot see the
    /// face's size (a larger face further away projects the same).
    ModelOnly,
    /// The face-anchored streaming fusion on the model's mesh with each frame's fitted face as
    /// its template: the depth data, smoothed as deviations from the fitted face.
    ModelFusion,
    /// [`Method::Raw`] with a filter on every vertex's track: what a user could do instead of
    /// fusing.
    RawFiltered(VertexFilter),
}

/// The vertex set a method's outputs live on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexKind {
    /// The image-plane mesh of the sequence (`FusionSetup`), the same for every such method.
    ImagePlane,
    /// The image-plane mesh with the SIFT anchors added (`FusionSetup::with_anchors` on
    /// [`MethodInput::sift_anchors`]).
    SiftAnchoredImagePlane,
    /// The face-anchored mesh ([`AnchoredInput::domain`]).
    Anchored,
    /// The morphable model's face region ([`ModelInput::domain`]).
    Model,
}

/// What the face-anchored methods are given on top of the depth.
#[derive(Clone, Copy, Debug)]
pub struct AnchoredInput<'a> {
    /// The face-anchored mesh on the canonical FaceMesh.
    pub domain: &'a FaceDomain,
    /// Canonical FaceMesh vertices (head coordinates, metres).
    pub template: &'a [[f64; 3]],
    /// The simulated tracker's landmarks and poses.
    pub tracking: &'a TrackedSequence,
    /// λ (mm⁴ of the canonical face), μ of the face-anchored fusion.
    pub weights: Weights,
    /// What the model methods need (`None`: they cannot run).
    pub model: Option<ModelInput<'a>>,
}

/// What the model methods are given.
#[derive(Clone, Copy, Debug)]
pub struct ModelInput<'a> {
    /// The compact model fitted to the landmarks.
    pub model: &'a FaceModel,
    /// Its face region as a face-anchored mesh (the model's own triangles).
    pub domain: &'a FaceDomain,
    /// Its neutral face (head coordinates, metres): the finite-element domain.
    pub neutral: &'a [[f64; 3]],
    /// λ (mm⁴ of the model's face), μ of the model fusion.
    pub weights: Weights,
}

/// What every method is given: the camera, the sequence's meshing domain and reference
/// surface (as `visage fuse` derives them from the input), and the fusion parameters.
#[derive(Clone, Copy, Debug)]
pub struct MethodInput<'a> {
    pub k: &'a Intrinsics,
    /// Pixels valid in at least half of the frames.
    pub domain: &'a Mask,
    /// Per-pixel mean of the valid input depth.
    pub reference: &'a DepthMap,
    pub meshing: &'a MeshingOptions,
    /// λ, μ of the fusion methods (per-frame biharmonic uses μ = 0).
    pub weights: Weights,
    pub clip: &'a ClipOptions,
    /// Depth beyond this counts as missing, metres.
    pub max_depth_m: f64,
    /// The noisy depth frames.
    pub frames: &'a [DepthMap],
    /// Input of the face-anchored methods (`None`: they cannot run).
    pub anchored: Option<AnchoredInput<'a>>,
    /// Anchor points of [`Method::StreamingSiftAnchors`] (pixels; `None`: it cannot run).
    pub sift_anchors: Option<&'a [[f64; 2]]>,
    /// Per-frame keypoints of [`Method::FaceAnchoredFairedSift`] (`None`: it cannot run).
    pub fairing_keypoints: Option<FairingKeypoints<'a>>,
}

/// A method's output on one sequence.
#[derive(Clone, Debug)]
pub struct MethodRun {
    /// One #V × 3 field per input frame (metres, camera coordinates).
    pub solutions: Vec<Mat<f64>>,
    pub vertices: VertexKind,
    /// Per frame, the raw surface at the same vertices when it differs from
    /// [`Method::Raw`]'s (face-anchored methods, SIFT anchors); the reference of the curvature
    /// improvement.
    pub raw: Option<Vec<Mat<f64>>>,
    /// Wall time of the per-frame work over the whole sequence, seconds (the fixed set-up —
    /// mesh, operators, factorisation — excluded; it is shared by every frame).
    pub seconds: f64,
    /// [`Method::FaceAnchoredFairedSift`]: the mean fraction of vertices at full fairing
    /// weight (`None` for the other methods).
    pub full_weight_fraction: Option<f64>,
}

impl Method {
    /// The key of the method in `results.json`.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Raw => "raw",
            Method::PerFrameBiharmonic => "per_frame_biharmonic",
            Method::Streaming => "streaming",
            Method::StreamingSiftAnchors => "streaming_sift_anchors",
            Method::Clip => "clip",
            Method::Taubin { .. } => "taubin",
            Method::FaceAnchored => "face_anchored",
            Method::FaceAnchoredClip => "face_anchored_clip",
            Method::FaceAnchoredFaired => "face_anchored_faired",
            Method::FaceAnchoredFairedSift => "face_anchored_faired_sift",
            Method::ModelOnly => "model_only",
            Method::ModelFusion => "model_fusion",
            Method::RawFiltered(VertexFilter::Ema) => "raw_ema",
            Method::RawFiltered(VertexFilter::OneEuro) => "raw_one_euro",
            Method::RawFiltered(VertexFilter::Kalman) => "raw_kalman",
            Method::RawFiltered(VertexFilter::Gaussian) => "raw_gaussian",
        }
    }

    /// Runs the method on `input`.
    ///
    /// # Errors
    /// A face-anchored method without [`MethodInput::anchored`], or a failing set-up.
    pub fn run(&self, input: &MethodInput<'_>) -> Result<MethodRun, EvalError> {
        let setup = || FusionSetup::new(input.k, input.domain, input.reference, input.meshing);
        let anchored = || {
            input.anchored.ok_or(EvalError::InvalidConfig {
                name: "method",
                value: self.name().into(),
                reason: "needs the tracker input (landmarks and poses)",
            })
        };
        match *self {
            Method::Raw => Ok(raw(&setup()?, input, 0)),
            Method::Taubin { iterations } => Ok(raw(&setup()?, input, iterations)),
            Method::RawFiltered(filter) => {
                let mut run = raw(&setup()?, input, 0);
                let start = Instant::now();
                run.solutions = filter.apply(&run.solutions);
                run.seconds += start.elapsed().as_secs_f64();
                Ok(run)
            }
            Method::PerFrameBiharmonic => fused(
                setup()?,
                input,
                Weights {
                    mu: 0.0,
                    ..input.weights
                },
                None,
            ),
            Method::Streaming => fused(setup()?, input, input.weights, None),
            Method::StreamingSiftAnchors => {
                let anchors = input.sift_anchors.ok_or(EvalError::InvalidConfig {
                    name: "method",
                    value: self.name().into(),
                    reason: "needs the SIFT anchors of the sequence",
                })?;
                let setup = FusionSetup::with_anchors(
                    input.k,
                    input.domain,
                    input.reference,
                    input.meshing,
                    anchors,
                )?;
                // The raw surface on these vertices: the curvature improvement's reference.
                let reference = raw(&setup, input, 0).solutions;
                let mut run = fused(setup, input, input.weights, None)?;
                run.vertices = VertexKind::SiftAnchoredImagePlane;
                run.raw = Some(reference);
                Ok(run)
            }
            Method::Clip => fused(setup()?, input, input.weights, Some(input.clip)),
            Method::FaceAnchored => face_anchored(input, &anchored()?, None),
            Method::FaceAnchoredClip => face_anchored(input, &anchored()?, Some(input.clip)),
            Method::FaceAnchoredFaired => {
                let a = anchored()?;
                let mut run = face_anchored(input, &a, None)?;
                let start = Instant::now();
                fair_frames(&mut run.solutions, &a.domain.triangles)?;
                run.seconds += start.elapsed().as_secs_f64();
                Ok(run)
            }
            Method::FaceAnchoredFairedSift => {
                let a = anchored()?;
                let keypoints = input.fairing_keypoints.ok_or(EvalError::InvalidConfig {
                    name: "method",
                    value: self.name().into(),
                    reason: "needs the SIFT keypoints of every frame",
                })?;
                let mut run = face_anchored(input, &a, None)?;
                let start = Instant::now();
                let fraction = fair_frames_weighted(
                    &mut run.solutions,
                    &a.domain.triangles,
                    input.k,
                    &keypoints,
                )?;
                run.seconds += start.elapsed().as_secs_f64();
                run.full_weight_fraction = Some(fraction);
                Ok(run)
            }
            Method::ModelOnly | Method::ModelFusion => {
                let a = anchored()?;
                let m = a.model.ok_or(EvalError::InvalidConfig {
                    name: "method",
                    value: self.name().into(),
                    reason: "needs the face model",
                })?;
                model_run(input, &a, &m, *self == Method::ModelFusion)
            }
        }
    }
}

/// The smoothing length of [`Method::FaceAnchoredFaired`] (`visage run --fair 2`).
pub const BENCHMARK_FAIRING_LENGTH_M: f64 = 0.002;

/// Fairs every frame's surface in place: the system from the first frame, each solve from the
/// previous result.
fn fair_frames(solutions: &mut [Mat<f64>], triangles: &[[u32; 3]]) -> Result<(), EvalError> {
    let Some(first) = solutions.first() else {
        return Ok(());
    };
    let first = mat_points(first);
    let weights = vec![1.0; first.len()];
    let mut system = visage_fem::FairingSystem::new(
        &first,
        triangles,
        &weights,
        BENCHMARK_FAIRING_LENGTH_M.powi(-4),
        visage_fem::Preconditioner::Cholesky,
    )?;
    let mut warm = first;
    for s in solutions.iter_mut() {
        let targets = mat_points(s);
        let (faired, _, _) = system.solve(&targets, &warm, 1e-10, 200);
        set_points(s, &faired);
        warm = faired;
    }
    Ok(())
}

/// The rows of a #V × 3 solution as points.
fn mat_points(m: &Mat<f64>) -> Vec<[f64; 3]> {
    (0..m.nrows())
        .map(|i| [m[(i, 0)], m[(i, 1)], m[(i, 2)]])
        .collect()
}

/// Writes `points` into the rows of a #V × 3 solution.
fn set_points(m: &mut Mat<f64>, points: &[[f64; 3]]) {
    for (i, p) in points.iter().enumerate() {
        for (c, &v) in p.iter().enumerate() {
            m[(i, c)] = v;
        }
    }
}

/// [`fair_frames`] with each frame's weights from `keypoints` (its vertices projected with
/// `k`, [`keypoint_weights`], or the random control's): the operators measured on the first
/// frame, a system built and factored per frame, each solve from the previous result. Returns
/// the mean fraction of vertices at full weight.
fn fair_frames_weighted(
    solutions: &mut [Mat<f64>],
    triangles: &[[u32; 3]],
    k: &Intrinsics,
    keypoints: &FairingKeypoints<'_>,
) -> Result<f64, EvalError> {
    let Some(first) = solutions.first() else {
        return Ok(0.0);
    };
    let first = mat_points(first);
    let order = keypoints
        .random_control
        .map(|seed| control_order(first.len(), seed));
    let mut warm = first.clone();
    let mut full = 0.0;
    for (index, s) in solutions.iter_mut().enumerate() {
        let targets = mat_points(s);
        let found = keypoints.frames.get(index).map_or(&[][..], Vec::as_slice);
        let mut weights = keypoint_weights(&targets, k, found, &keypoints.options);
        if let Some(order) = &order {
            weights = random_control_weights(&weights, &keypoints.options, order);
        }
        full += weights.iter().filter(|&&w| w >= 1.0).count() as f64 / weights.len() as f64;
        let mut system = visage_fem::FairingSystem::new(
            &first,
            triangles,
            &weights,
            BENCHMARK_FAIRING_LENGTH_M.powi(-4),
            visage_fem::Preconditioner::Cholesky,
        )?;
        let (faired, _, _) = system.solve(&targets, &warm, 1e-10, 200);
        set_points(s, &faired);
        warm = faired;
    }
    Ok(full / solutions.len() as f64)
}

/// Back-projection with in-painted holes, then `taubin` smoothing passes (0: none). A frame
/// without one valid vertex repeats the previous output (zeros at the start).
fn raw(setup: &FusionSetup, input: &MethodInput<'_>, taubin: usize) -> MethodRun {
    let n = setup.vertex_count();
    let (mut x, mut scratch) = (Mat::<f64>::zeros(n, 3), Mat::<f64>::zeros(n, 3));
    let mut valid = vec![false; n];
    let mut solutions = Vec::with_capacity(input.frames.len());
    let start = Instant::now();
    for depth in input.frames {
        if setup.sample_vertices(depth, input.max_depth_m, &mut x, &mut valid) > 0 {
            setup.inpaint(&mut x, &valid);
            taubin_smooth(&mut x, &setup.ring, taubin, &mut scratch);
        }
        solutions.push(x.clone());
    }
    MethodRun {
        solutions,
        vertices: VertexKind::ImagePlane,
        raw: None,
        seconds: start.elapsed().as_secs_f64(),
        full_weight_fraction: None,
    }
}

/// The paper's fusion with `weights`: streaming, or with `clip` the whole-clip solve started
/// from the streaming solutions (frames without data are carried and left out of the clip
/// system, as `visage fuse --mode clip` does).
fn fused(
    setup: FusionSetup,
    input: &MethodInput<'_>,
    weights: Weights,
    clip: Option<&ClipOptions>,
) -> Result<MethodRun, EvalError> {
    let n = setup.vertex_count();
    let system = FusionSystem::new(setup.ops.clone(), weights)?;
    let mut fuser = ImagePlaneFuser::new(setup, system, input.max_depth_m);
    let mut solutions = Vec::with_capacity(input.frames.len());
    let (mut bs, mut members) = (Vec::new(), Vec::new());
    let start = Instant::now();
    for (index, depth) in input.frames.iter().enumerate() {
        let r = fuser.process(depth)?;
        match r.status {
            FrameStatus::NoData => solutions.push(
                solutions
                    .last()
                    .cloned()
                    .unwrap_or_else(|| Mat::zeros(n, 3)),
            ),
            FrameStatus::Solved | FrameStatus::Carried => {
                solutions.push(to_mat(fuser.solution()));
                if clip.is_some() {
                    bs.push(fuser.clip_state().b);
                    members.push(index);
                }
            }
        }
    }
    if let Some(options) = clip {
        let mut xs: Vec<Mat<f64>> = members.iter().map(|&i| solutions[i].clone()).collect();
        solve_clip(fuser.system_mut(), &bs, &mut xs, options);
        for (x, &i) in xs.into_iter().zip(&members) {
            solutions[i] = x;
        }
    }
    Ok(MethodRun {
        solutions,
        vertices: VertexKind::ImagePlane,
        raw: None,
        seconds: start.elapsed().as_secs_f64(),
        full_weight_fraction: None,
    })
}

/// A frame without data: the previous output repeated as solution and raw surface (zeros at
/// the start).
fn repeat_last(solutions: &mut Vec<Mat<f64>>, raw: &mut Vec<Mat<f64>>, n: usize) {
    let last = solutions.last().cloned();
    solutions.push(last.clone().unwrap_or_else(|| Mat::zeros(n, 3)));
    raw.push(last.unwrap_or_else(|| Mat::zeros(n, 3)));
}

fn to_mat(points: &[[f64; 3]]) -> Mat<f64> {
    Mat::from_fn(points.len(), 3, |i, c| points[i][c])
}

/// The face-anchored fusion: per frame the tracked landmarks place the vertices, the noisy
/// depth is sampled there (`FrameDepth::Map`) and the pose compensates the temporal term; with
/// `clip`, the whole-clip solve in head coordinates over the solved frames (frames without
/// data are carried, as in [`fused`]).
fn face_anchored(
    input: &MethodInput<'_>,
    a: &AnchoredInput<'_>,
    clip: Option<&ClipOptions>,
) -> Result<MethodRun, EvalError> {
    let mut fuser = AnchoredFuser::new(
        a.domain.clone(),
        a.template,
        *input.k,
        a.weights,
        input.max_depth_m,
    )?;
    let n = a.domain.vertex_count();
    let (mut solutions, mut raw) = (Vec::new(), Vec::new());
    let (mut bs, mut xs, mut members) = (Vec::new(), Vec::new(), Vec::new());
    let mut poses = Vec::new();
    let start = Instant::now();
    for (index, depth) in input.frames.iter().enumerate() {
        let r = fuser.process(&AnchoredFrame {
            template: None,
            landmarks_px: &a.tracking.landmarks_px[index],
            pose: a.tracking.poses[index],
            depth: FrameDepth::Map(depth),
        })?;
        if r.status == FrameStatus::NoData {
            repeat_last(&mut solutions, &mut raw, n);
            continue;
        }
        solutions.push(to_mat(fuser.solution()));
        raw.push(to_mat(fuser.raw()));
        if clip.is_some() && r.status == FrameStatus::Solved {
            let state = fuser.clip_state();
            bs.push(state.b);
            xs.push(state.x);
            poses.push((state.pose, state.offset));
            members.push(index);
        }
    }
    if let Some(options) = clip {
        solve_clip(fuser.system_mut(), &bs, &mut xs, options);
        for ((x, &i), (pose, offset)) in xs.into_iter().zip(&members).zip(poses) {
            fuser.load_clip_state(&ClipState {
                b: Mat::new(),
                x,
                pose,
                offset,
            });
            solutions[i] = to_mat(fuser.solution());
        }
    }
    Ok(MethodRun {
        solutions,
        vertices: VertexKind::Anchored,
        raw: Some(raw),
        seconds: start.elapsed().as_secs_f64(),
        full_weight_fraction: None,
    })
}

/// The model methods: per frame the model is fitted to the tracked landmarks and its fitted
/// face — posed, projected, and as the frame's template — drives the anchored fuser on the
/// model's mesh, which measures the face's scale from the depth map. `fuse`: the fused
/// surface; otherwise the fitted face at that scale ([`AnchoredFuser::posed_template`]).
fn model_run(
    input: &MethodInput<'_>,
    a: &AnchoredInput<'_>,
    m: &ModelInput<'_>,
    fuse: bool,
) -> Result<MethodRun, EvalError> {
    let mut fuser = AnchoredFuser::new(
        m.domain.clone(),
        m.neutral,
        *input.k,
        m.weights,
        input.max_depth_m,
    )?;
    let mut fitter = FaceFitter::new(m.model, FitOptions::exact_landmarks());
    let n = m.domain.vertex_count();
    let (mut shape, mut camera, mut pixels) = (Vec::new(), Vec::new(), Vec::new());
    let (mut solutions, mut raw) = (Vec::new(), Vec::new());
    let start = Instant::now();
    for (index, depth) in input.frames.iter().enumerate() {
        let fit = fitter.fit(input.k, &a.tracking.landmarks_px[index], None);
        m.model
            .shape(fitter.identity(), &fit.expression, &mut shape);
        camera.clear();
        camera.extend(shape.iter().map(|&p| fit.pose.apply(p)));
        pixels.clear();
        pixels.extend(camera.iter().map(|&p| input.k.project(p)));
        let r = fuser.process(&AnchoredFrame {
            landmarks_px: &pixels,
            pose: fit.pose,
            depth: FrameDepth::Map(depth),
            template: Some(&shape),
        })?;
        if r.status == FrameStatus::NoData {
            repeat_last(&mut solutions, &mut raw, n);
            continue;
        }
        solutions.push(if fuse {
            to_mat(fuser.solution())
        } else {
            let posed: Vec<[f64; 3]> = fuser.posed_template().collect();
            to_mat(&posed)
        });
        raw.push(to_mat(fuser.raw()));
    }
    Ok(MethodRun {
        solutions,
        vertices: VertexKind::Model,
        raw: Some(raw),
        seconds: start.elapsed().as_secs_f64(),
        full_weight_fraction: None,
    })
}
