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
//! [`run_clip`] is `visage run` as one call: its flags as the fields of [`RunOptions`], the
//! output folder with its exports written as the command line writes them.
//!
//! # Conventions
//! - Camera coordinates: x right, y down, z forward, metres; pixel `(i, j)`'s centre at
//!   `(i, j)` ([`Intrinsics`]).
//! - Frame indices are input indices (a video's frame number, a folder's file number).
//! - The face mesh's vertex `i < 468` is FaceMesh landmark `i`.

#![forbid(unsafe_code)]

mod clip_run;
mod config;
mod depth_folder;
mod depth_stage;
mod error;
mod face_depth;
mod first_faces;
mod folder_run;
mod input;
mod keypoint_motion;
mod landmark_reader;
pub mod live;
mod pipeline;
mod pipeline_options;
pub mod process_stats;
mod quality;
mod reconstructor;
mod recorder;
mod rigid_jitter;
mod run_options;
mod sink;
mod stages;

pub use clip_run::{run_clip, ClipProgress, FaceRun};
pub use config::{
    check_fov, Builder, Camera, DepthSource, ModelSource, Parameters, TemporalMode,
    DEFAULT_SUBDIVISION,
};
pub use depth_folder::{fuse_depth_folder, FuseOptions};
pub use error::Error;
pub use face_depth::{render_faces_depth, render_surface_depth};
pub use first_faces::first_faces;
pub use folder_run::{run_into, FolderOptions, FolderRun};
pub use input::{FrameFilter, Input, KeptFrames};
pub use landmark_reader::{FrameFaces, LandmarkReader};
pub use pipeline_options::{PipelineOptions, DEFAULT_DEPTH_SCALE};
pub use reconstructor::{error_chain, FrameResult, Identity, Reconstructor, RunOutcome};
pub use run_options::{Faces, RunOptions};
pub use sink::{FrameSink, MeshFrame};
pub use stages::{Irises, Surfaces};

pub use visage_camera::{DepthKind, Intrinsics, RigidTransform, DEFAULT_FOV_DEG};
pub use visage_depth::{
    AlignMode, AlignedNetwork, DepthError, DepthNetwork, DepthProvider, DepthRequest,
    DepthSequence, EdgeMask, NetworkConfig, NetworkRegion, OutputKind, ProvidedDepth, Registration,
    RgbdLayout, RgbdOptions, RgbdRecording,
};
pub use visage_export::{ExportOptions, ExportSummary};
pub use visage_face::{
    FaceTarget, CLIP_LATENCY_FRAMES, DEFAULT_FRAME_INTERVAL_S, DEFAULT_LANDMARK_SMOOTHING,
    DEFAULT_LATENCY_FRAMES, MAX_LATENCY_FRAMES,
};
pub use visage_fem::{ClipOptions, Weights};
pub use visage_fusion::{MeshKind, MeshingOptions, DEFAULT_MAX_DEPTH_M};
pub use visage_mesh::io::{write_ply, PlyFormat};
pub use visage_mesh::{TriMesh, TriangulationKind};
pub use visage_morphable::{FaceModel, FitOptions};
pub use visage_rig::{BlendshapeFrame, BlendshapeTrack, ARKIT_BLENDSHAPES};
pub use visage_run_folder as run_folder;
pub use visage_run_folder::{
    file_names, write_atomically, write_json_atomically, FrameMetrics, FrameSelection, FrameStatus,
    LandmarksFrame, OutputDir, Report, RunStatus, RunSummary,
};
pub use visage_video::{Frame, VideoError};
