//! Variational surface fusion (paper Sections 2 and 4, ERRATA 1–6 and 15–18): a fixed mesh,
//! its finite-element operators factored once, and per frame only a right-hand side.
//!
//! Two designs share the [`SurfaceFuser`] interface:
//! - [`ImagePlaneFuser`]: the paper's mesh, fixed on the image plane over a depth sequence's
//!   domain ([`FusionSetup`], [`SequenceSurvey`]);
//! - [`AnchoredFuser`]: a mesh whose vertices are fixed points of the face ([`FaceDomain`]),
//!   with a temporal term that follows the head pose.
//!
//! [`SurfaceFusion`] runs either on a tracked face video, frame by frame or over a whole clip.

#![forbid(unsafe_code)]

mod anchored_fuser;
mod error;
mod face_domain;
mod fused_frame;
mod fusion_setup;
mod image_domain;
mod image_plane_fuser;
mod point_locator;
mod sequence_survey;
mod solver_bench;
mod surface_fuser;
mod surface_fusion;

pub use anchored_fuser::{
    AnchoredFrame, AnchoredFuser, FrameDepth, ANCHORED_WEIGHTS_FACE, ANCHORED_WEIGHTS_MAP,
    DOMAIN_UNITS_PER_METRE, MODEL_WEIGHTS_MAP, SCALE_FILTER_RATIO,
};
pub use error::FusionError;
pub use face_domain::{Anchor, FaceDomain, MAX_SUBDIVISION};
pub use fused_frame::{FrameStatus, FusedFrame};
pub use fusion_setup::{FusionSetup, MeshingOptions, INPAINT_SWEEPS, MAX_MESH_VERTICES};
pub use image_plane_fuser::{to_positions, ImagePlaneFuser, DEFAULT_MAX_DEPTH_M};
pub use sequence_survey::{SequenceSurvey, DOMAIN_MAJORITY};
pub use solver_bench::{bench_solver, SizeReport, SolverBench, VariantReport};
pub use surface_fuser::{solve_clip_frames, ClipFrame, ClipState, SurfaceFuser};
pub use surface_fusion::{
    FaceFrame, FaceTemplate, FusedSurfaces, FusionParams, LandmarkAnchor, MeshKind, ModelFrame,
    SurfaceFusion,
};
