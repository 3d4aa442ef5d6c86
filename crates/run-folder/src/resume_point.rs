//! The record of a run that `visage run --resume` compares against ([`RunDescription`], in
//! `metrics.json`) and of where a resumed run continued ([`ResumePoint`]); the logic is in
//! [`crate::prepare_resume`].

use serde::Serialize;
use visage_camera::Intrinsics;

/// Which of an input's frames a run processes: every `every`-th, at most `max_frames` of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct FrameSelection {
    pub every: usize,
    pub max_frames: Option<usize>,
}

/// A run's parameters as `metrics.json` records them (the pipeline's own type): a resumed run
/// must have the same.
pub trait RunParameters: Serialize {
    /// Why a run with these parameters cannot be continued part-way (and what to do instead),
    /// or `None` when it can.
    fn cannot_resume(&self) -> Option<&'static str>;

    /// Frames the landmark smoother waits for before giving a frame out: a run's last ones
    /// went out without that look-ahead.
    fn latency_frames(&self) -> usize;

    /// Whether the model is fitted (and so the blendshape curves written).
    fn fits_model(&self) -> bool;
}

/// What defines a run: a folder's files are continued only by the same one. Written into
/// `metrics.json` when the run starts ([`crate::OutputDir::write_running`]).
#[derive(Debug, Serialize)]
pub struct RunDescription<'a, P> {
    /// The input as given on the command line.
    pub input: &'a str,
    /// The input file by content, when it is one file (a resumed run must read the same bytes,
    /// wherever the path is typed from).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub input_file: Option<&'a crate::InputFile>,
    pub intrinsics: &'a Intrinsics,
    pub parameters: &'a P,
    pub selection: FrameSelection,
}

impl<P> Clone for RunDescription<'_, P> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<P> Copy for RunDescription<'_, P> {}

/// Kept frames a resumed run processes again to warm its temporal state up (10 s at 30 fps,
/// ~3 s of work). The frame-to-frame state (the landmark smoother, the fusion's previous
/// surface) forgets its start within ~30 frames; the clip-long estimates (the identity, the
/// resting face the blendshapes are measured from) are taken over the warm-up instead of
/// every frame before, which needs more frames to come close.
pub const WARM_UP_FRAMES: usize = 300;

/// Where a resumed run continues, and what the files keep from before.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ResumePoint {
    /// The previous run's status (`"running"`: it was killed).
    pub previous_status: String,
    /// Input index of the last frame kept; the run goes on with the next one.
    pub after_frame: usize,
    /// Frames kept (landmarks records).
    pub frames: usize,
    /// Of them, the meshed ones (point cache samples).
    pub meshed: usize,
    /// Blendshape frames kept.
    pub blendshape_frames: usize,
    /// Frames the previous run had written that are done again: its last ones, which a kill
    /// may have left partly written, or which went out without the landmark smoother's
    /// look-ahead.
    pub redone: usize,
    /// Kept frames processed again before the resume point, their outputs not written again,
    /// so that the temporal state (the smoothers, the fusion's previous surface, the identity)
    /// is warm when the new frames come: at most [`WARM_UP_FRAMES`].
    pub warm_up_frames: usize,
    /// The warm-up starts after this input index (`None`: at the input's start).
    #[serde(skip)]
    pub warm_up_after: Option<usize>,
    /// Input indices of the frames kept.
    #[serde(skip)]
    pub frame_indices: Vec<usize>,
    /// Input indices of the frames whose surfaces the point cache keeps, one per sample: the
    /// meshed frames (every frame when the previous run had finished the cache). Empty: the
    /// cache starts afresh.
    #[serde(skip)]
    pub cache_indices: Vec<usize>,
    /// The kept frames' records for `metrics.json`, in order: the previous run's own where its
    /// `metrics.json` has them, else rebuilt from `landmarks.json` (index, source, status,
    /// pose; marked `"restored": true`) for a run killed before it wrote them. The resumed
    /// run's `metrics.json` lists these, then its new frames, so that it lists every frame the
    /// files hold.
    #[serde(skip)]
    pub kept_records: Vec<serde_json::Value>,
}
