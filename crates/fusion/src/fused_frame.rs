//! What fusing one frame did — the same record for both fusion designs.

use serde::Serialize;

/// How a frame was fused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameStatus {
    /// Solved from its own data.
    Solved,
    /// No valid depth: the previous solution was carried over.
    Carried,
    /// No valid depth and no previous solution: no surface.
    NoData,
}

/// What a fuser measured on one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FusedFrame {
    pub status: FrameStatus,
    /// Fraction of the data with a valid depth: of the domain's pixels (image-plane mesh) or of
    /// the vertices (face-anchored mesh).
    pub valid_fraction: f64,
    /// Sampling, hole filling and right-hand-side assembly (seconds).
    pub rhs_seconds: f64,
    /// The streaming solve (seconds).
    pub solve_seconds: f64,
    /// Relative residual of the frame's linear system.
    pub relative_residual: f64,
}

impl FusedFrame {
    /// A frame that has not been solved (yet): `status`, nothing measured.
    pub(crate) fn unsolved(status: FrameStatus) -> Self {
        FusedFrame {
            status,
            valid_fraction: 0.0,
            rhs_seconds: 0.0,
            solve_seconds: 0.0,
            relative_residual: 0.0,
        }
    }
}
