//! The benchmark's metrics (ERRATA 13), accumulated over sequences.
//!
//! A method's outputs s_k (#V × 3, camera coordinates, metres) live on its own vertex set, and
//! each vertex stands for a point whose ground truth (GT) is known ([`VertexTruth`]):
//! - **image-plane vertices** (the paper's mesh): vertex i is the pixel x_i with unit ray ρ_i
//!   (Eq. 2.1); its GT point is g_k(i) ρ_i, g_k(i) the GT distance along ρ_i (bilinear in the
//!   rendered depth; undefined off the head), and it is in the **face set** F_k when its
//!   nearest pixel sees a [`visage_morphable::Region::Face`] triangle in the GT render;
//! - **face-anchored vertices**: vertex i is a fixed point of the face; its GT point
//!   g_k(i) is that material point on frame k's GT mesh (through the
//!   [`visage_morphable::CanonicalCorrespondence`]), and every vertex is in F_k.
//!
//! Metrics:
//! - **surface error** e = distance from s_k(i) to the GT mesh of frame k (exact point-to-mesh),
//!   over i ∈ F_k; `rmse_mm` = √mean e², `median_mm` = median e, pooled over frames and sequences.
//! - **surface error after the best scale** (`rmse_scaled_mm`): the same for σ·s_k(i), σ one
//!   scale about the camera centre per method and sequence, the least-squares fit of the outputs
//!   to their GT points (σ = Σ s·g / Σ s·s over the face set of every frame); `scale_error` =
//!   mean |σ − 1| over sequences. Depth known only up to scale (a monocular network's, aligned
//!   to a face fitted to landmarks) cannot tell a large face far away from a small one nearby:
//!   this separates the shape error from that unobservable size.
//! - **jitter** (mm/frame) = √mean ‖(s_k(i) − s_{k−1}(i)) − (g_k(i) − g_{k−1}(i))‖² over
//!   i ∈ F_k ∩ F_{k−1} with g defined at both: the frame-to-frame motion the method adds on top
//!   of the true motion of the same point (for image-plane vertices, of the surface along the
//!   same ray).
//! - **lag** (frames) = argmin over τ ∈ [0, [`LAG_MAX`]] of
//!   E(τ) = mean ‖(s_k(i) − s_{k−1}(i)) − (g_{k−τ}(i) − g_{k−τ−1}(i))‖² over moving frames k
//!   ([`moving_frames`]) and i ∈ F_k with g defined at k−τ and k−τ−1, refined by a parabola
//!   through the minimum and its neighbours: how many frames late the method's motion follows
//!   the true motion of the same points. Comparing motions rather than positions makes the lag
//!   blind to static offsets (a landmark's bias over the skin, the correspondence's residual),
//!   so it means the same for both vertex sets; E(0) is the jitter² over those frames.
//! - **curvature improvement** = mean over frames of mean |H|(raw) / mean |H|(method), and
//!   **roughness** = mean over frames of the mean one-ring normal deviation (radians), both
//!   over the interior vertices of the method's mesh (`visage_fem::SurfaceMetrics`, ERRATA 13);
//!   "raw" is the raw surface sampled at the same vertices. Raw's improvement is 1 by
//!   definition.
//! - **ms_per_frame**: the method's per-frame wall time (set-up excluded).

use faer::Mat;
use visage_camera::vec3::{distance2, sub};
use visage_fem::SurfaceMetrics;
use visage_fusion::{to_positions, FaceDomain, FusionSetup};

use crate::synthesis::SyntheticSequence;
use visage_mesh::point_to_mesh::TriangleGrid;

/// Largest lag searched, frames.
pub const LAG_MAX: usize = 8;
/// A frame counts as moving for the lag when the RMS GT motion of the face-region vertices of
/// the model is at least this, mm/frame.
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
    /// The same after each sequence's best scale; Σ |σ − 1| and sequences.
    scaled_sq: f64,
    scaled_n: usize,
    scale_error: f64,
    scale_sequences: usize,
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
    /// RMSE after each sequence's best scale about the camera centre (module docs).
    pub rmse_scaled_mm: f64,
    /// Mean |σ − 1| of that scale.
    pub scale_error: f64,
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
            rmse_scaled_mm: 1e3 * (self.scaled_sq / self.scaled_n.max(1) as f64).sqrt(),
            scale_error: self.scale_error / self.scale_sequences.max(1) as f64,
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

/// The ground truth of one vertex set over a sequence.
#[derive(Clone, Debug, PartialEq)]
pub struct VertexTruth {
    /// `[frame][vertex]`: whether the vertex is in the face set F_k.
    pub face: Vec<Vec<bool>>,
    /// `[frame][vertex]`: GT camera-space point the vertex stands for, metres.
    pub points: Vec<Vec<Option<[f64; 3]>>>,
}

impl VertexTruth {
    /// Image-plane vertices of `setup`: face set from the GT face mask at the nearest pixel,
    /// points `g_k(i) ρ_i`.
    pub fn image_plane(seq: &SyntheticSequence, setup: &FusionSetup) -> VertexTruth {
        let k = &seq.k;
        let points = &setup.mesh.points;
        VertexTruth {
            face: seq
                .frames
                .iter()
                .map(|f| {
                    points
                        .iter()
                        .map(|p| f.face.get(p[0].round() as i64, p[1].round() as i64))
                        .collect()
                })
                .collect(),
            points: seq
                .frames
                .iter()
                .map(|f| {
                    points
                        .iter()
                        .zip(&setup.rays)
                        .map(|(p, r)| {
                            f.depth
                                .sample_ray_distance(k, p[0], p[1])
                                .map(|g| r.map(|c| g * c))
                        })
                        .collect()
                })
                .collect(),
        }
    }

    /// Face-anchored vertices of `domain`, from the GT positions of its template vertices per
    /// frame (`template_truth[k]`, one point per template vertex): every vertex is on the face.
    ///
    /// # Panics
    /// If a frame does not have one point per template vertex.
    #[track_caller]
    pub fn anchored(domain: &FaceDomain, template_truth: &[Vec<[f64; 3]>]) -> VertexTruth {
        let n = domain.vertex_count();
        let mut at = vec![[0.0; 3]; n];
        VertexTruth {
            face: vec![vec![true; n]; template_truth.len()],
            points: template_truth
                .iter()
                .map(|t| {
                    domain.interpolate(t, &mut at);
                    at.iter().map(|&p| Some(p)).collect()
                })
                .collect(),
        }
    }
}

impl VertexTruth {
    /// The morphable model's face-region vertices (`0..vertex_count`, ICT-FaceKit order): the
    /// GT point of vertex i is GT vertex i, and a vertex is in the face set when the GT render
    /// sees it — its nearest pixel is a face pixel whose depth is within
    /// [`VISIBLE_TOLERANCE_M`] of the vertex's — as the image-plane vertices count only what
    /// the camera sees.
    pub fn model(seq: &SyntheticSequence, vertex_count: usize) -> VertexTruth {
        let k = &seq.k;
        let mut face = Vec::with_capacity(seq.frames.len());
        let mut points = Vec::with_capacity(seq.frames.len());
        for f in &seq.frames {
            let vertices = &f.vertices[..vertex_count];
            face.push(
                vertices
                    .iter()
                    .map(|&p| {
                        let [u, v] = k.project(p);
                        let (x, y) = (u.round() as i64, v.round() as i64);
                        f.face.get(x, y) && {
                            let z = f.depth.data[y as usize * k.width as usize + x as usize];
                            (z as f64 - p[2]).abs() <= VISIBLE_TOLERANCE_M
                        }
                    })
                    .collect(),
            );
            points.push(vertices.iter().map(|&p| Some(p)).collect());
        }
        VertexTruth { face, points }
    }
}

/// How far (metres) behind the rendered surface a model vertex may lie and still count as seen.
pub const VISIBLE_TOLERANCE_M: f64 = 0.005;

/// A method's vertex set: its mesh (for the ERRATA 13 metrics) and its ground truth.
#[derive(Clone, Copy, Debug)]
pub struct VertexSet<'a> {
    pub triangles: &'a [[u32; 3]],
    /// Per vertex: on the mesh boundary.
    pub boundary: &'a [bool],
    pub truth: &'a VertexTruth,
}

/// One method's outputs on a sequence, to be scored.
#[derive(Clone, Copy, Debug)]
pub struct Scored<'a> {
    pub vertices: VertexSet<'a>,
    /// One #V × 3 field per frame.
    pub solutions: &'a [Mat<f64>],
    /// The raw surface at the same vertices per frame (reference of the curvature improvement).
    pub raw: &'a [Mat<f64>],
}

/// Per frame: whether it counts for the lag — k > [`LAG_MAX`] and the RMS GT motion of the
/// model's face-region vertices from frame k−1 is at least [`MOVING_MM_PER_FRAME`].
pub fn moving_frames(seq: &SyntheticSequence) -> Vec<bool> {
    let face = visage_morphable::Region::Face.range();
    (0..seq.frames.len())
        .map(|k| {
            if k <= LAG_MAX {
                return false;
            }
            let (a, b) = (&seq.frames[k].vertices, &seq.frames[k - 1].vertices);
            let s: f64 = face
                .clone()
                .map(|i| (0..3).map(|c| (a[i][c] - b[i][c]).powi(2)).sum::<f64>())
                .sum();
            1e3 * (s / face.len() as f64).sqrt() >= MOVING_MM_PER_FRAME
        })
        .collect()
}

fn row(m: &Mat<f64>, i: usize) -> [f64; 3] {
    [m[(i, 0)], m[(i, 1)], m[(i, 2)]]
}

/// Evaluates every method's outputs on one sequence into `accumulators` (same order as `runs`).
///
/// # Panics
/// If a run does not have one field per frame of `seq`, or its fields, raw surfaces and truth
/// disagree on the vertex count.
#[track_caller]
pub fn evaluate_sequence(
    seq: &SyntheticSequence,
    runs: &[Scored<'_>],
    accumulators: &mut [MetricAccumulator],
) {
    let n_frames = seq.frames.len();
    assert_eq!(runs.len(), accumulators.len());
    for r in runs {
        let n = r.vertices.boundary.len();
        assert!(r.solutions.len() == n_frames && r.raw.len() == n_frames);
        assert!(r
            .solutions
            .iter()
            .chain(r.raw)
            .all(|m| m.nrows() == n && m.ncols() == 3));
        assert!(
            r.vertices.truth.face.len() == n_frames && r.vertices.truth.points.len() == n_frames
        );
    }
    for acc in accumulators.iter_mut() {
        if acc.frame_err.len() < n_frames {
            acc.frame_err.resize(n_frames, (0.0, 0));
            acc.frame_jit.resize(n_frames, (0.0, 0));
        }
    }
    let moving = moving_frames(seq);
    let mut quality: Vec<SurfaceMetrics> = runs
        .iter()
        .map(|r| {
            SurfaceMetrics::new(
                r.vertices.boundary.len(),
                r.vertices.triangles,
                r.vertices.boundary,
            )
        })
        .collect();
    // Each run's best scale about the camera centre over the sequence.
    let scales: Vec<f64> = runs
        .iter()
        .map(|r| {
            let (mut sg, mut ss) = (0.0, 0.0);
            for k in 0..n_frames {
                let (face, points) = (&r.vertices.truth.face[k], &r.vertices.truth.points[k]);
                for i in (0..face.len()).filter(|&i| face[i]) {
                    if let Some(g) = points[i] {
                        let p = row(&r.solutions[k], i);
                        sg += (0..3).map(|c| p[c] * g[c]).sum::<f64>();
                        ss += (0..3).map(|c| p[c] * p[c]).sum::<f64>();
                    }
                }
            }
            if ss > 0.0 && sg > 0.0 {
                sg / ss
            } else {
                1.0
            }
        })
        .collect();
    for (acc, sigma) in accumulators.iter_mut().zip(&scales) {
        acc.scale_error += (sigma - 1.0).abs();
        acc.scale_sequences += 1;
    }
    let mut positions = Vec::new();
    for (k, &moving_k) in moving.iter().enumerate() {
        let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
        for (r, sigma) in runs.iter().zip(&scales) {
            for (i, _) in r.vertices.truth.face[k].iter().enumerate().filter(|f| *f.1) {
                for c in 0..3 {
                    let v = r.solutions[k][(i, c)];
                    lo[c] = lo[c].min(v).min(sigma * v);
                    hi[c] = hi[c].max(v).max(sigma * v);
                }
            }
        }
        if lo[0] > hi[0] {
            continue;
        }
        let gt = &seq.frames[k].vertices;
        let grid = TriangleGrid::new(gt, &seq.triangles, lo, hi, GRID_MARGIN_M, GRID_CELL_M);
        for (((r, acc), quality), &sigma) in runs
            .iter()
            .zip(accumulators.iter_mut())
            .zip(&mut quality)
            .zip(&scales)
        {
            let (s, truth) = (&r.solutions[k], r.vertices.truth);
            let n = s.nrows();
            let face = &truth.face[k];
            // Surface error.
            for i in (0..n).filter(|&i| face[i]) {
                if let Some(e) = grid.distance(row(s, i)) {
                    acc.errors.push(e);
                    acc.frame_err[k].0 += e * e;
                    acc.frame_err[k].1 += 1;
                }
                if let Some(e) = grid.distance(row(s, i).map(|c| sigma * c)) {
                    acc.scaled_sq += e * e;
                    acc.scaled_n += 1;
                }
            }
            // Jitter.
            if k > 0 {
                let p = &r.solutions[k - 1];
                for i in (0..n).filter(|&i| face[i] && truth.face[k - 1][i]) {
                    if let (Some(g1), Some(g0)) = (truth.points[k][i], truth.points[k - 1][i]) {
                        let d2: f64 = (0..3)
                            .map(|c| ((s[(i, c)] - p[(i, c)]) - (g1[c] - g0[c])).powi(2))
                            .sum();
                        acc.jitter_sq += d2;
                        acc.jitter_n += 1;
                        acc.frame_jit[k].0 += d2;
                        acc.frame_jit[k].1 += 1;
                    }
                }
            }
            // Lag: the method's motion against the true motion τ frames earlier.
            if moving_k {
                let p = &r.solutions[k - 1];
                for tau in 0..=LAG_MAX {
                    let (g1, g0) = (&truth.points[k - tau], &truth.points[k - tau - 1]);
                    for i in (0..n).filter(|&i| face[i]) {
                        if let (Some(a), Some(b)) = (g1[i], g0[i]) {
                            let v: [f64; 3] = std::array::from_fn(|c| s[(i, c)] - p[(i, c)]);
                            acc.lag_sq[tau] += distance2(v, sub(a, b));
                            acc.lag_n[tau] += 1;
                        }
                    }
                }
            }
            // Surface quality (ERRATA 13).
            positions.resize(n, [0.0; 3]);
            to_positions(r.raw[k].as_ref(), &mut positions);
            let raw_quality = quality.evaluate(&positions);
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
