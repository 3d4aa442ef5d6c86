//! A visage run's output folder, and everything that reads or writes its files: the one table
//! of their names ([`file_names`]), the streams a run writes frame by frame ([`OutputDir`]: the
//! point cache, `landmarks.json`, the blendshape curves; [`LiveLinkCsvWriter`],
//! [`BlendshapesJsonWriter`]), the records' schemas ([`LandmarksFrame`], [`Report`] and the
//! rest of `metrics.json`), writing so that a reader never sees half a file
//! ([`write_atomically`]), a frame's surface read back from the point cache
//! ([`read_mesh_or_cache`]), one run per folder ([`claim`], [`inspect`], [`clear_outputs`]) and continuing
//! a run that stopped part-way ([`prepare_resume`]).
//!
//! Every file appears complete or not at all: a stream is written under `<name>.tmp` and
//! renamed when finished, so after a kill the frames so far are there for `--resume`.

#![forbid(unsafe_code)]

mod atomic_write;
mod blendshapes_json;
mod file_guide;
pub mod file_names;
mod folder;
mod folder_lock;
mod input_file;
mod json_records;
mod landmarks;
mod live_link_csv;
mod metrics;
mod output;
mod point_cache;
mod resume;
mod resume_point;
mod stream;

mod error;

pub use atomic_write::{tmp_path, write_atomically, write_json_atomically};
pub use blendshapes_json::BlendshapesJsonWriter;
pub use error::RunFolderError;
pub use file_guide::{FileUse, FILE_GUIDE, PER_FRAME_MESHES};
pub use folder::{claim, clear_outputs, inspect, Claimed, Cleared, FolderContents};
pub use folder_lock::{FolderLock, LockHolder};
pub use input_file::{sha256_of, InputFile};
pub use json_records::{scan_frames, scan_records, Scan};
pub use landmarks::{FaceRecord, LandmarksFrame, PoseRecord};
pub use live_link_csv::{
    live_link_timecode, read_live_link_csv, LiveLinkCsvWriter, LiveLinkRow, LiveLinkTake,
};
pub use metrics::{
    DepthAlignmentMetrics, DepthAlignmentSummary, FrameMetrics, FrameQuality, FrameStatus,
    FusedAndRaw, KeypointMotionMetrics, KeypointMotionSummary, MeshSummary, Percentiles,
    PoseMetrics, QualitySummary, Report, RunStatus, RunSummary, RunTiming, SolverSummary,
    StageTimes,
};
pub use output::{camera_to_y_up, MeshOutput, OutputDir, CACHE_MATERIAL, DEFAULT_TIMECODE_FPS};
pub use point_cache::{read_cache_sample, read_mesh_or_cache};
pub use resume::{prepare_resume, ResumeState};
pub use resume_point::{
    FrameSelection, ResumePoint, RunDescription, RunParameters, WARM_UP_FRAMES,
};
