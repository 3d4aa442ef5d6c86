//! The interface both fusion designs share: the image-plane mesh ([`crate::ImagePlaneFuser`])
//! and the face-anchored mesh ([`crate::AnchoredFuser`]).

use faer::Mat;
use visage_camera::RigidTransform;
use visage_fem::{solve_clip, ClipOptions, ClipReport, FusionSystem, SurfaceQuality};

/// A frame's state kept for the whole-clip solve (ERRATA 1 and 17): its data right-hand side
/// and streaming solution in the solver's coordinates (#V × 3 each), and the pose that maps
/// those coordinates to the camera (the identity for the image-plane mesh, the head pose for
/// the face-anchored one).
#[derive(Clone, Debug)]
pub struct ClipState {
    pub b: Mat<f64>,
    pub x: Mat<f64>,
    pub pose: RigidTransform,
    /// Added to `x` before `pose` maps it to the camera: the face-anchored mesh's frame
    /// template at the face's scale (its solver works on the deviation from it); empty (0 × 3)
    /// for the image-plane mesh.
    pub offset: Mat<f64>,
}

/// Streaming fusion on a fixed mesh, the part both designs share: the fused and the raw
/// surface of the last frame, its quality and its state for the whole-clip solve. Each design
/// has a `process(&mut self, frame) -> Result<FusedFrame, FusionError>` of its own input type
/// (a depth map; tracked landmarks, pose and depth), allocation-free once it has a previous
/// solution, with the operators factored once (ERRATA 4). Surfaces are #V camera-space points
/// in metres.
pub trait SurfaceFuser {
    /// The mesh's triangles (indices into the surfaces).
    fn triangles(&self) -> &[[u32; 3]];

    /// The last fused surface.
    fn solution(&self) -> &[[f64; 3]];

    /// The last raw surface on the same mesh (holes as the solver filled them).
    fn raw(&self) -> &[[f64; 3]];

    /// Forgets the temporal history (lost track, shot cut; ERRATA 18).
    fn reset(&mut self);

    /// Mean |H| and roughness (ERRATA 13) of the last raw surface and of the last solution.
    fn frame_quality(&mut self) -> (SurfaceQuality, SurfaceQuality);

    /// The last frame's state for the whole-clip solve.
    fn clip_state(&self) -> ClipState;

    /// The factored system, for [`visage_fem::solve_clip`].
    fn system_mut(&mut self) -> &mut FusionSystem;

    /// Makes a clip-solved frame the current one: its [`ClipState`] (the clip solution in
    /// `x`) and its raw surface.
    fn load_clip_solution(&mut self, state: &ClipState, raw: &[[f64; 3]]);
}

/// A frame kept for the whole-clip solve: its [`ClipState`], its raw surface and (video) its
/// landmark pixels.
pub struct ClipFrame {
    pub state: ClipState,
    pub raw: Vec<[f64; 3]>,
    pub landmarks_px: Vec<[f64; 2]>,
}

/// Solves the clip system (ERRATA 1, 17) over `frames` — consecutive frames of one sequence or
/// face track — on `fuser`'s streaming factorisation, from their streaming solutions; their
/// states' `x` hold the clip solutions afterwards. Load one back with
/// [`SurfaceFuser::load_clip_solution`].
pub fn solve_clip_frames(
    fuser: &mut dyn SurfaceFuser,
    frames: &mut [ClipFrame],
    options: &ClipOptions,
) -> ClipReport {
    let take = |m: &mut Mat<f64>| std::mem::replace(m, Mat::new());
    let b: Vec<Mat<f64>> = frames.iter_mut().map(|f| take(&mut f.state.b)).collect();
    let mut x: Vec<Mat<f64>> = frames.iter_mut().map(|f| take(&mut f.state.x)).collect();
    let report = solve_clip(fuser.system_mut(), &b, &mut x, options);
    for ((f, x), b) in frames.iter_mut().zip(x).zip(b) {
        f.state.x = x;
        f.state.b = b;
    }
    report
}
