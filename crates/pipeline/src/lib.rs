//! Sequence-level orchestration of visage: depth sequences in, fused mesh sequences and
//! metrics out. The stages live in the library crates (`visage-camera`, `visage-mesh`,
//! `visage-fem`); this crate fixes the per-sequence set-up and drives the per-frame loop —
//! on the paper's image-plane mesh ([`Fuser`]) or on the face-anchored mesh with a
//! pose-compensated temporal term ([`FaceDomain`], [`AnchoredFuser`]).

mod anchored_fuser;
mod atomic_write;
mod depth_sequence;
mod error;
mod face_domain;
mod fuse;
mod fusion_setup;
mod report;

pub use anchored_fuser::{
    AnchoredFrame, AnchoredFuser, AnchoredResult, FrameDepth, ANCHORED_WEIGHTS_FACE,
    ANCHORED_WEIGHTS_MAP, DOMAIN_UNITS_PER_METRE, SCALE_SMOOTHING,
};
pub use atomic_write::write_atomically;
pub use depth_sequence::{DepthSequence, SequenceSurvey, DOMAIN_MAJORITY};
pub use error::PipelineError;
pub use face_domain::{Anchor, FaceDomain, MAX_SUBDIVISION};
pub use fuse::{
    fuse_sequence, to_positions, FrameResult, FuseOptions, Fuser, Mode, DEFAULT_MAX_DEPTH_M,
};
pub use fusion_setup::{FusionSetup, MeshingOptions, INPAINT_SWEEPS};
pub use report::{
    FrameMetrics, FrameQuality, FrameStatus, FuseReport, FuseSummary, MeshSummary, SolverSummary,
};
