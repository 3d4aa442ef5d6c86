//! `visage run` and `visage bench`: RGB video in, a fused metric face mesh per frame out
//! (issue #6). Stages on threads with bounded queues ([`stages`]), the two fusion designs
//! ([`surface_fusion`]), and the run's metrics ([`run_metrics`]).

mod image_domain;
mod point_locator;
mod process_stats;
mod rigid_jitter;
mod run_metrics;
mod stages;
mod surface_fusion;

pub use run_metrics::{FrameMetrics, RunSummary};
pub use stages::{run_pipeline, DepthSource, Output, RunConfig, RunOutcome, TemporalMode};
pub use surface_fusion::{FusionParams, MeshKind, SurfaceFusion};
