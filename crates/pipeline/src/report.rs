//! The `metrics.json` written by a fusion run.

use serde::Serialize;
use visage_fem::{ClipReport, SurfaceQuality, Weights};

use crate::fuse::FuseOptions;

/// Outcome of one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameStatus {
    /// Solved from its own data.
    Solved,
    /// No valid depth: the previous solution was carried over (and written).
    Carried,
    /// No valid depth and no previous solution: no mesh written.
    NoData,
}

/// Per-frame metrics (ERRATA 13 for the curvature and roughness definitions).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameMetrics {
    pub index: usize,
    pub source: String,
    pub status: FrameStatus,
    /// Fraction of the domain's pixels with valid depth.
    pub valid_fraction: f64,
    /// Right-hand-side assembly time (ms).
    pub rhs_ms: f64,
    /// Solve time (ms): the streaming step; in clip mode, the clip solve's time per frame.
    pub solve_ms: f64,
    /// Relative residual of this frame's linear system.
    pub relative_residual: f64,
    /// Curvature and roughness, raw and fused (flattened into the frame's record).
    #[serde(flatten)]
    pub quality: FrameQuality,
}

/// Mean |H| and roughness of a frame's raw and fused surfaces (ERRATA 13).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FrameQuality {
    /// Mean |H| (1/m) of the raw surface on the mesh.
    pub mean_abs_h_raw: f64,
    /// Mean |H| (1/m) after regularisation.
    pub mean_abs_h: f64,
    /// `mean_abs_h_raw / mean_abs_h` (0 when the fused surface is flat).
    pub curvature_improvement: f64,
    /// Roughness (radians, mean normal deviation from the one-ring) of the raw surface.
    pub roughness_raw: f64,
    /// Roughness (radians) after regularisation.
    pub roughness: f64,
}

impl FrameQuality {
    /// The record of a raw and a fused surface's measurements.
    pub fn of(raw: &SurfaceQuality, fused: &SurfaceQuality) -> Self {
        FrameQuality {
            mean_abs_h_raw: raw.mean_abs_h,
            mean_abs_h: fused.mean_abs_h,
            curvature_improvement: if fused.mean_abs_h > 0.0 {
                raw.mean_abs_h / fused.mean_abs_h
            } else {
                0.0
            },
            roughness_raw: raw.roughness,
            roughness: fused.roughness,
        }
    }
}

/// Size and kind of the fixed mesh.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeshSummary {
    pub vertices: usize,
    pub triangles: usize,
    pub boundary_vertices: usize,
    pub flatness_ratio: f64,
    /// Whether depth-aware flips were applied, and how many.
    pub depth_aware: bool,
    pub depth_aware_flips: usize,
}

/// Set-up cost of the solver.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SolverSummary {
    /// Stored values of the Cholesky factor.
    pub factor_nnz: usize,
    /// Symbolic + numeric factorisation time (ms), once per sequence.
    pub factor_ms: f64,
    /// Meshing + assembly time (ms), once per sequence.
    pub setup_ms: f64,
    /// Clip mode: the PCG solve over the whole clip.
    pub clip: Option<ClipReport>,
    pub clip_ms: Option<f64>,
}

/// Totals over the frames.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FuseSummary {
    pub frames: usize,
    pub solved: usize,
    pub carried: usize,
    pub no_data: usize,
    pub median_solve_ms: f64,
    pub max_relative_residual: f64,
    pub mean_curvature_improvement: f64,
    pub mean_roughness_raw: f64,
    pub mean_roughness: f64,
}

/// Everything `metrics.json` holds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FuseReport {
    /// `"complete"`, or `"failed"` with `error` set (frames up to the failure are listed).
    pub status: String,
    pub error: Option<String>,
    pub input: String,
    pub width: u32,
    pub height: u32,
    pub parameters: FuseOptions,
    pub weights: Weights,
    pub mesh: MeshSummary,
    pub solver: SolverSummary,
    pub frames: Vec<FrameMetrics>,
    pub summary: FuseSummary,
}

impl FuseSummary {
    /// Totals of `frames`.
    pub fn of(frames: &[FrameMetrics]) -> Self {
        let solved: Vec<&FrameMetrics> = frames
            .iter()
            .filter(|f| f.status == FrameStatus::Solved)
            .collect();
        let count = |s| frames.iter().filter(|f| f.status == s).count();
        let mean = |f: &dyn Fn(&FrameMetrics) -> f64| {
            if solved.is_empty() {
                0.0
            } else {
                solved.iter().map(|m| f(m)).sum::<f64>() / solved.len() as f64
            }
        };
        let mut times: Vec<f64> = solved.iter().map(|f| f.solve_ms).collect();
        times.sort_by(f64::total_cmp);
        FuseSummary {
            frames: frames.len(),
            solved: solved.len(),
            carried: count(FrameStatus::Carried),
            no_data: count(FrameStatus::NoData),
            median_solve_ms: times.get(times.len() / 2).copied().unwrap_or(0.0),
            max_relative_residual: solved
                .iter()
                .map(|f| f.relative_residual)
                .fold(0.0, f64::max),
            mean_curvature_improvement: mean(&|f| f.quality.curvature_improvement),
            mean_roughness_raw: mean(&|f| f.quality.roughness_raw),
            mean_roughness: mean(&|f| f.quality.roughness),
        }
    }
}
