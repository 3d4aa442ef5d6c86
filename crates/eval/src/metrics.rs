//! The benchmark's metrics (issue #5, item 5; ERRATA 13), accumulated over sequences.
//!
//! The methods' meshes live on the image plane: vertex i is the pixel position x_i with unit
//! ray ρ_i (Eq. 2.1), the same for every frame and method. With the ground truth (GT) of
//! frame k — its posed mesh and its exact rendered depth — define, per vertex:
//! - **face set** F_k: vertices whose nearest pixel sees a [`visage_morphable::Region::Face`]
//!   triangle in the GT render;
//! - g_k(i): the GT distance along ρ_i (bilinear in the rendered depth; undefined off the head).
//!
//! Metrics of a method with outputs s_k (#V × 3):
//! - **surface error** e = distance from s_k(i) to the GT mesh of frame k (exact point-to-mesh),
//!   over i ∈ F_k; `rmse_mm` = √mean e², `median_mm` = median e, pooled over frames and sequences.
//! - **jitter** (mm/frame) = √mean ‖(s_k(i) − s_{k−1}(i)) − (g_k(i) − g_{k−1}(i)) ρ_i‖² over
//!   i ∈ F_k ∩ F_{k−1} with g defined at both: the frame-to-frame motion the method adds on top
//!   of the true surface motion along the same ray.
//! - **lag** (frames) = argmin over τ ∈ [0, [`LAG_MAX`]] of
//!   E(τ) = mean (s_k(i)·ρ_i − g_{k−τ}(i))² over moving frames k ≥ [`LAG_MAX`] (GT motion RMS
//!   ≥ [`MOVING_MM_PER_FRAME`]) and i ∈ F_k with g_{k−τ}(i) defined, refined by a parabola
//!   through the minimum and its neighbours: which past ground truth the output resembles most
//!   while the head moves.
//! - **curvature improvement** = mean over frames of mean |H|(raw) / mean |H|(method), and
//!   **roughness** = mean over frames of the mean one-ring normal deviation (radians), both
//!   over the interior vertices of the whole image-plane mesh (`visage_fem::SurfaceMetrics`,
//!   ERRATA 13). Raw's improvement is 1 by definition.
//! - **ms_per_frame**: the method's per-frame wall time (set-up excluded).

use faer::Mat;
use visage_fem::SurfaceMetrics;
use visage_pipeline::{to_positions, FusionSetup};

use crate::point_to_mesh::TriangleGrid;
use crate::synthesis::SyntheticSequence;

/// Largest lag searched, frames.
pub const LAG_MAX: usize = 8;
/// A frame counts as moving for the lag when the RMS GT motion along the rays of its face
/// vertices is at least this, mm/frame.
pub const MOVING_MM_PER_FRAME: f64 = 0.5;
/// Side of the point-to-mesh grid cells, metres.
const GRID_CELL_M: f64 = 0.005;
/// Triangles farther than this from every query point's box are not binned, metres.
const GRID_MARGIN_M: f64 = 0.05;

/// Running sums of one method's metrics over the sequences.
#[derive(Clone, Debug, Default)]
pub struct MetricAccumulator {
    /// Every face-vertex error, metres.
    errors: Vec<f64>,
    jitter_sq: f64,
    jitter_n: usize,
    lag_sq: [f64; LAG_MAX + 1],
    lag_n: [usize; LAG_MAX + 1],
    improvement: f64,
    roughness: f64,
    mean_abs_h: f64,
    quality_frames: usize,
    seconds: f64,
    frames: usize,
    /// Per frame index: Σ e², count; Σ jitter², count (summed over sequences).
    frame_err: Vec<(f64, usize)>,
    frame_jit: Vec<(f64, usize)>,
}

/// One method's metrics (the `methods.<name>` object of `results.json`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MethodSummary {
    pub rmse_mm: f64,
    pub median_mm: f64,
    /// mm/frame.
    pub jitter_mm: f64,
    pub lag_frames: f64,
    pub curvature_improvement: f64,
    /// Radians.
    pub roughness: f64,
    /// Mean |H|, 1/m.
    pub mean_abs_h: f64,
    pub ms_per_frame: f64,
    /// Face-vertex samples behind rmse/median.
    pub samples: usize,
}

/// Per frame index, averaged over sequences: RMS error and jitter, mm.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PerFrame {
    pub rmse_mm: Vec<f64>,
    pub jitter_mm: Vec<f64>,
}

impl MetricAccumulator {
    /// The summary of everything accumulated.
    pub fn summary(&self) -> MethodSummary {
        let mut e = self.errors.clone();
        e.sort_by(f64::total_cmp);
        let n = e.len().max(1) as f64;
        let median = if e.is_empty() {
            f64::NAN
        } else if e.len() % 2 == 1 {
            e[e.len() / 2]
        } else {
            0.5 * (e[e.len() / 2 - 1] + e[e.len() / 2])
        };
        let q = self.quality_frames.max(1) as f64;
        MethodSummary {
            rmse_mm: 1e3 * (e.iter().map(|x| x * x).sum::<f64>() / n).sqrt(),
            median_mm: 1e3 * median,
            jitter_mm: 1e3 * (self.jitter_sq / self.jitter_n.max(1) as f64).sqrt(),
            lag_frames: self.lag(),
            curvature_improvement: self.improvement / q,
            roughness: self.roughness / q,
            mean_abs_h: self.mean_abs_h / q,
            ms_per_frame: 1e3 * self.seconds / self.frames.max(1) as f64,
            samples: e.len(),
        }
    }

    /// Per-frame RMS error and jitter (mm); frame 0's jitter is 0.
    pub fn per_frame(&self) -> PerFrame {
        let f = |v: &[(f64, usize)]| {
            v.iter()
                .map(|&(s, n)| 1e3 * (s / n.max(1) as f64).sqrt())
                .collect()
        };
        PerFrame {
            rmse_mm: f(&self.frame_err),
            jitter_mm: f(&self.frame_jit),
        }
    }

    /// Pooled E(τ), its argmin and parabolic refinement; NaN without moving frames.
    fn lag(&self) -> f64 {
        let e: Vec<f64> = (0..=LAG_MAX)
            .map(|t| {
                if self.lag_n[t] > 0 {
                    self.lag_sq[t] / self.lag_n[t] as f64
                } else {
                    f64::NAN
                }
            })
            .collect();
        if e.iter().any(|x| x.is_nan()) {
            return f64::NAN;
        }
        let best = (0..=LAG_MAX)
            .min_by(|&a, &b| e[a].total_cmp(&e[b]))
            .unwrap_or(0);
        if best == 0 || best == LAG_MAX {
            return best as f64;
        }
        let (a, b, c) = (e[best - 1], e[best], e[best + 1]);
        let denom = a - 2.0 * b + c;
        let shift = if denom > 0.0 {
            0.5 * (a - c) / denom
        } else {
            0.0
        };
        best as f64 + shift.clamp(-0.5, 0.5)
    }

    /// Adds a run's wall time over `frames` frames.
    pub fn add_time(&mut self, seconds: f64, frames: usize) {
        self.seconds += seconds;
        self.frames += frames;
    }
}

/// Per-sequence ground truth sampled at the image-plane vertices.
struct VertexTruth {
    /// [frame][vertex]: in the face set.
    face: Vec<Vec<bool>>,
    /// [frame][vertex]: GT ray distance, metres.
    ray: Vec<Vec<Option<f64>>>,
}

fn vertex_truth(seq: &SyntheticSequence, setup: &FusionSetup) -> VertexTruth {
    let k = &seq.k;
    let points = &setup.mesh.points;
    let face = seq
        .frames
        .iter()
        .map(|f| {
            points
                .iter()
                .map(|p| f.face.get(p[0].round() as i64, p[1].round() as i64))
                .collect()
        })
        .collect();
    let ray = seq
        .frames
        .iter()
        .map(|f| {
            points
                .iter()
                .map(|p| f.depth.sample_ray_distance(k, p[0], p[1]))
                .collect()
        })
        .collect();
    VertexTruth { face, ray }
}

/// Evaluates every method's outputs on one sequence into `accumulators` (same order as
/// `outputs`). `raw_index` is the position of the raw back-projection among `outputs`
/// (the reference of the curvature improvement). All outputs live on `setup`'s mesh.
///
/// # Panics
/// If an output does not have one #V × 3 field per frame of `seq`, or `raw_index` is out of range.
#[track_caller]
pub fn evaluate_sequence(
    seq: &SyntheticSequence,
    setup: &FusionSetup,
    outputs: &[&[Mat<f64>]],
    raw_index: usize,
    accumulators: &mut [MetricAccumulator],
) {
    let n_frames = seq.frames.len();
    let n = setup.vertex_count();
    assert!(outputs
        .iter()
        .all(|o| o.len() == n_frames && o.iter().all(|m| m.nrows() == n)));
    let truth = vertex_truth(seq, setup);
    let rays = &setup.rays;
    let mut quality = SurfaceMetrics::new(n, &setup.mesh.triangles, &setup.boundary);
    let mut positions = vec![[0.0; 3]; n];
    for acc in accumulators.iter_mut() {
        if acc.frame_err.len() < n_frames {
            acc.frame_err.resize(n_frames, (0.0, 0));
            acc.frame_jit.resize(n_frames, (0.0, 0));
        }
    }
    // Moving frames for the lag.
    let moving: Vec<bool> = (0..n_frames)
        .map(|k| {
            if k < LAG_MAX {
                return false;
            }
            let (mut s, mut c) = (0.0, 0usize);
            for i in 0..n {
                if let (true, Some(a), Some(b)) =
                    (truth.face[k][i], truth.ray[k][i], truth.ray[k - 1][i])
                {
                    s += (a - b) * (a - b);
                    c += 1;
                }
            }
            c > 0 && 1e3 * (s / c as f64).sqrt() >= MOVING_MM_PER_FRAME
        })
        .collect();

    for k in 0..n_frames {
        let face: Vec<usize> = (0..n).filter(|&i| truth.face[k][i]).collect();
        if face.is_empty() {
            continue;
        }
        let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
        for out in outputs {
            for &i in &face {
                for c in 0..3 {
                    lo[c] = lo[c].min(out[k][(i, c)]);
                    hi[c] = hi[c].max(out[k][(i, c)]);
                }
            }
        }
        let gt = &seq.frames[k].vertices;
        let grid = TriangleGrid::new(gt, &seq.triangles, lo, hi, GRID_MARGIN_M, GRID_CELL_M);
        to_positions(outputs[raw_index][k].as_ref(), &mut positions);
        let raw_quality = quality.evaluate(&positions);
        for (out, acc) in outputs.iter().zip(accumulators.iter_mut()) {
            let s = &out[k];
            // Surface error.
            for &i in &face {
                if let Some(e) = grid.distance([s[(i, 0)], s[(i, 1)], s[(i, 2)]]) {
                    acc.errors.push(e);
                    acc.frame_err[k].0 += e * e;
                    acc.frame_err[k].1 += 1;
                }
            }
            // Jitter.
            if k > 0 {
                let p = &out[k - 1];
                for &i in face.iter().filter(|&&i| truth.face[k - 1][i]) {
                    if let (Some(g1), Some(g0)) = (truth.ray[k][i], truth.ray[k - 1][i]) {
                        let d2: f64 = (0..3)
                            .map(|c| ((s[(i, c)] - p[(i, c)]) - (g1 - g0) * rays[i][c]).powi(2))
                            .sum();
                        acc.jitter_sq += d2;
                        acc.jitter_n += 1;
                        acc.frame_jit[k].0 += d2;
                        acc.frame_jit[k].1 += 1;
                    }
                }
            }
            // Lag.
            if moving[k] {
                for tau in 0..=LAG_MAX {
                    for &i in &face {
                        if let Some(g) = truth.ray[k - tau][i] {
                            let d = (0..3).map(|c| s[(i, c)] * rays[i][c]).sum::<f64>();
                            acc.lag_sq[tau] += (d - g) * (d - g);
                            acc.lag_n[tau] += 1;
                        }
                    }
                }
            }
            // Surface quality (ERRATA 13).
            to_positions(s.as_ref(), &mut positions);
            let q = quality.evaluate(&positions);
            acc.improvement += if q.mean_abs_h > 0.0 {
                raw_quality.mean_abs_h / q.mean_abs_h
            } else {
                0.0
            };
            acc.roughness += q.roughness;
            acc.mean_abs_h += q.mean_abs_h;
            acc.quality_frames += 1;
        }
    }
}
