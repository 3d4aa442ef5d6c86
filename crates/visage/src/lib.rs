//! visage: temporally stable, metric 3-D face meshes from ordinary RGB video, on a CPU.
//!
//! Per frame: the face is tracked and its 468 landmarks regressed (MediaPipe's networks, run in
//! pure Rust), a metric face is fitted to them with the camera's intrinsics, a depth is taken
//! (the fitted face's surface, or a depth map per frame), and the surface is fused on a fixed
//! mesh by a variational method — data fidelity, a biharmonic smoothness term and a temporal
//! term that follows the head — whose matrix is factored once per clip, so a frame costs one
//! right-hand side and one solve.
//!
//! # Frames in, meshes out
#![cfg_attr(all(model_files, shared_data, ffmpeg), doc = "```")]
#![cfg_attr(not(all(model_files, shared_data, ffmpeg)), doc = "```ignore")]
//! use visage::{Input, Reconstructor};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let path = std::path::Path::new("face.mp4");
//! # let path = &visage_testdata::shared_dir().join("data/video/lp_d18.mp4");
//! let input = Input::open(path)?;
//! # let input = input.max_frames(12)?;
//! let builder = Reconstructor::builder();
//! # let builder = builder.models_dir(visage_testdata::models_dir());
//! let mut reconstructor = builder.build_for(&input)?;
//! for frame in input {
//!     let result = reconstructor.process(&frame?)?;
//!     if let Some(mesh) = result.mesh() {
//!         // 1.8k vertices in metres, camera coordinates (x right, y down, z forward).
//!         println!("frame {}: nose tip at {:?}", result.index(), mesh.vertices[1]);
//! #       assert!(mesh.vertices[1][2] > 0.2 && mesh.vertices.len() == 1833);
//!     }
//! }
//! # Ok(())
//! # }
//! ```
//! [`Reconstructor::process`] is causal and single-threaded; [`Reconstructor::run`] runs a
//! whole input with decoding, tracking and fusion on their own threads, in streaming or clip
//! mode ([`TemporalMode`]), into a [`FrameSink`] such as [`OutputDir`] (the point cache
//! `sequence.pc2` with `mesh.obj`, PLY meshes on request, `landmarks.json`, `metrics.json`). `examples/reconstruct.rs` writes a PLY per frame.
//!
//! # Conventions
//! - Camera coordinates: x right, y down, z forward, metres; pixel `(i, j)`'s centre at
//!   `(i, j)` ([`Intrinsics`]).
//! - Frame indices are input indices (a video's frame number, a folder's file number).
//! - The face mesh's vertex `i < 468` is FaceMesh landmark `i`.

#![forbid(unsafe_code)]

mod animation;
mod atomic_write;
mod config;
mod depth_folder;
mod depth_stage;
mod error;
mod face_depth;
mod gaze;
mod histogram;
mod input;
mod json_records;
mod keypoint_motion;
mod landmark_smoothing;
mod landmarks;
mod lid_gate;
mod metrics;
mod output;
mod pipeline;
mod process_stats;
mod quality;
mod reconstructor;
mod recorder;
mod rest_pose;
mod resume;
mod resume_point;
mod rigid_jitter;
mod run_folder;
mod shot_cut;
mod sink;
mod stages;

pub use animation::{
    live_link_angles, live_link_timecode, BlendshapeFrame, BlendshapeTrack, BlendshapesJsonWriter,
    IctSource, IctToArkit, LiveLinkCsvWriter, ARKIT_BLENDSHAPES, ARKIT_BLENDSHAPE_COUNT,
    BLENDSHAPES_CSV, BLENDSHAPES_JSON, ICT_EXPRESSIONS, ICT_TO_ARKIT, LIVE_LINK_BLENDSHAPES,
    LIVE_LINK_ROTATIONS, LIVE_LINK_VALUE_COUNT,
};
pub use atomic_write::{write_atomically, write_json_atomically};
pub use config::{
    check_fov, Builder, Camera, DepthSource, ModelSource, Parameters, TemporalMode,
    DEFAULT_SUBDIVISION,
};
pub use depth_folder::{fuse_depth_folder, FuseOptions};
pub use error::Error;
pub use face_depth::{render_faces_depth, render_surface_depth};
pub use gaze::{eye_gaze, eye_look_weights, EyeGaze};
pub use input::{FrameSelection, Input, KeptFrames};
pub use keypoint_motion::{
    FACE_MARGIN, INLIER_THRESHOLD_M, MAX_FACE_CROP_PX, MAX_FACE_KEYPOINTS, MIN_INLIERS,
};
pub use landmark_smoothing::{
    CLIP_LATENCY_FRAMES, DEFAULT_DISTANCE_SMOOTHING, DEFAULT_FRAME_INTERVAL_S,
    DEFAULT_LANDMARK_SMOOTHING, DEFAULT_LATENCY_FRAMES, MAX_LATENCY_FRAMES,
};
pub use landmarks::{FaceRecord, LandmarksFrame, PoseRecord};
pub use metrics::{
    DepthAlignmentMetrics, DepthAlignmentSummary, FrameMetrics, FrameQuality, FrameStatus,
    KeypointMotionSummary, MeshSummary, Percentiles, PoseMetrics, Report, RunStatus, RunSummary,
    RunTiming, SolverSummary, StageTimes,
};
pub use output::{
    camera_to_y_up, OutputDir, CACHE_MATERIAL, CACHE_MATERIAL_FILE, CACHE_MESH_FILE,
    DEFAULT_TIMECODE_FPS, POINT_CACHE_FILE,
};
pub use pipeline::QUEUE_CAPACITY;
pub use quality::{FusedAndRaw, QualitySummary};
pub use reconstructor::{error_chain, FrameResult, Identity, Reconstructor, RunOutcome};
pub use rest_pose::{lips_closed, RestPose, CLOSED_LIP_GAP};
pub use resume::{prepare_resume, ResumeState};
pub use resume_point::{ResumePoint, RunDescription, WARM_UP_FRAMES};
pub use rigid_jitter::rigid_residual_rms;
pub use run_folder::{
    clear_outputs, inspect as inspect_output_folder, FolderContents, FACE_FOLDER_PREFIX,
    OUTPUT_FILES, OUTPUT_FOLDERS,
};
pub use shot_cut::{CUT_FACE_JUMP, CUT_PICTURE_CHANGE};
pub use sink::{FrameSink, MeshFrame};
pub use stages::Surfaces;

pub use visage_camera::{DepthKind, Intrinsics, RigidTransform, DEFAULT_FOV_DEG};
pub use visage_depth::{
    AlignMode, AlignedNetwork, DepthError, DepthNetwork, DepthProvider, DepthRequest,
    DepthSequence, EdgeMask, NetworkConfig, NetworkRegion, OutputKind, ProvidedDepth, Registration,
    RgbdLayout, RgbdOptions, RgbdRecording,
};
pub use visage_face::FaceTarget;
pub use visage_fem::{ClipOptions, Weights};
pub use visage_fusion::{MeshKind, MeshingOptions, DEFAULT_MAX_DEPTH_M};
pub use visage_mesh::io::{write_ply, PlyFormat};
pub use visage_mesh::{TriMesh, TriangulationKind};
pub use visage_morphable::{FaceModel, FitOptions};
pub use visage_video::Frame;
