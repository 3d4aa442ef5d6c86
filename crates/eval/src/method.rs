//! The methods compared by the benchmark (issue #5, item 4). Each is a function of the same
//! input — the noisy depth sequence, the camera and the sequence's meshing domain — and returns
//! one vertex field per frame on the same image-plane mesh (#V × 3, metres, camera
//! coordinates), so metrics compare like with like. Adding a method is a variant here and a
//! line in [`Method::run`].

use std::time::Instant;

use faer::Mat;
use visage_camera::{DepthMap, Intrinsics};
use visage_fem::{solve_clip, ClipOptions, FusionSystem, Weights};
use visage_mesh::Mask;
use visage_pipeline::{FrameStatus, Fuser, FusionSetup, MeshingOptions};

use crate::taubin::taubin_smooth;
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
    /// The exact whole-clip minimiser (ERRATA 1, 4, 5), PCG from the streaming solutions.
    Clip,
    /// [`Method::Raw`] followed by Taubin λ|μ smoothing with this many iterations.
    Taubin { iterations: usize },
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
}

/// A method's output on one sequence.
#[derive(Clone, Debug)]
pub struct MethodRun {
    /// One #V × 3 field per input frame (metres, camera coordinates).
    pub solutions: Vec<Mat<f64>>,
    /// Wall time of the per-frame work over the whole sequence, seconds (the fixed set-up —
    /// mesh, operators, factorisation — excluded; it is shared by every frame).
    pub seconds: f64,
}

impl Method {
    /// The key of the method in `results.json`.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Raw => "raw",
            Method::PerFrameBiharmonic => "per_frame_biharmonic",
            Method::Streaming => "streaming",
            Method::Clip => "clip",
            Method::Taubin { .. } => "taubin",
        }
    }

    /// Runs the method on `input`.
    pub fn run(&self, input: &MethodInput<'_>) -> Result<MethodRun, EvalError> {
        let setup = FusionSetup::new(input.k, input.domain, input.reference, input.meshing)?;
        match *self {
            Method::Raw => Ok(raw(setup, input, 0)),
            Method::Taubin { iterations } => Ok(raw(setup, input, iterations)),
            Method::PerFrameBiharmonic => fused(
                setup,
                input,
                Weights {
                    mu: 0.0,
                    ..input.weights
                },
                None,
            ),
            Method::Streaming => fused(setup, input, input.weights, None),
            Method::Clip => fused(setup, input, input.weights, Some(input.clip)),
        }
    }
}

/// Back-projection with in-painted holes, then `taubin` smoothing passes (0: none). A frame
/// without one valid vertex repeats the previous output (zeros at the start).
fn raw(setup: FusionSetup, input: &MethodInput<'_>, taubin: usize) -> MethodRun {
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
        seconds: start.elapsed().as_secs_f64(),
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
    let mut fuser = Fuser::new(setup, system, input.max_depth_m);
    let mut solutions = Vec::with_capacity(input.frames.len());
    let (mut bs, mut members) = (Vec::new(), Vec::new());
    let start = Instant::now();
    for (index, depth) in input.frames.iter().enumerate() {
        let r = fuser.process(depth);
        match r.status {
            FrameStatus::NoData => solutions.push(
                solutions
                    .last()
                    .cloned()
                    .unwrap_or_else(|| Mat::zeros(n, 3)),
            ),
            FrameStatus::Solved | FrameStatus::Carried => {
                solutions.push(fuser.solution().to_owned());
                if clip.is_some() {
                    bs.push(fuser.rhs().to_owned());
                    members.push(index);
                }
            }
        }
    }
    if let Some(options) = clip {
        let mut xs: Vec<Mat<f64>> = members.iter().map(|&i| solutions[i].clone()).collect();
        solve_clip(fuser.solver_mut().system_mut(), &bs, &mut xs, options);
        for (x, &i) in xs.into_iter().zip(&members) {
            solutions[i] = x;
        }
    }
    Ok(MethodRun {
        solutions,
        seconds: start.elapsed().as_secs_f64(),
    })
}
