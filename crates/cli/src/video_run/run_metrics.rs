//! The `metrics.json` of `visage run` and the JSON of `visage bench`: per-frame stage times,
//! solver and surface figures, head pose; summary with throughput, CPU use, peak memory and the
//! issue #6 quality figures (rigid-aligned jitter, landmark reprojection error).

use serde::Serialize;
use visage_camera::{Intrinsics, RigidTransform};
use visage_pipeline::FrameQuality;

use super::rigid_jitter::JitterMeter;

/// Outcome of one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
    /// Fused from its own depth; a mesh was written.
    Solved,
    /// A face but no valid depth: the previous surface was carried over (mesh written).
    Carried,
    /// No face found: no mesh; the fusion's history restarts at the next face.
    NoFace,
    /// A face but no depth and no previous surface: no mesh.
    NoData,
}

/// Wall-clock milliseconds of each stage for one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StageTimes {
    /// Reading/decoding the frame (FFmpeg pipe or image file).
    pub decode: f64,
    /// Face tracking: landmark network, and the detector when the track was lost.
    pub track: f64,
    /// Metric face fit (pose + metric landmarks).
    pub fit: f64,
    /// Depth map: `--depth DIR` PNG read, or image mode's face rasterisation (face mode with
    /// face depth intersects the fitted surface inside the fusion: 0).
    pub depth: f64,
    /// Fusion: right-hand side, solve, curvature and roughness figures.
    pub fuse: f64,
    /// Writing the mesh(es) and the landmarks record.
    pub write: f64,
}

impl StageTimes {
    pub const NAMES: [&'static str; 6] = ["decode", "track", "fit", "depth", "fuse", "write"];

    pub fn values(&self) -> [f64; 6] {
        [
            self.decode,
            self.track,
            self.fit,
            self.depth,
            self.fuse,
            self.write,
        ]
    }
}

/// Head pose `X_cam = R · X_canonical + t` and its Z-Y-X Euler angles (degrees).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PoseMetrics {
    pub rotation: [[f64; 3]; 3],
    pub translation_m: [f64; 3],
    pub yaw_deg: f64,
    pub pitch_deg: f64,
    pub roll_deg: f64,
}

impl PoseMetrics {
    pub fn of(pose: &RigidTransform) -> Self {
        let r = pose.rotation;
        PoseMetrics {
            rotation: r,
            translation_m: pose.translation,
            yaw_deg: (-r[2][0]).clamp(-1.0, 1.0).asin().to_degrees(),
            pitch_deg: r[2][1].atan2(r[2][2]).to_degrees(),
            roll_deg: r[1][0].atan2(r[0][0]).to_degrees(),
        }
    }
}

/// One frame of `metrics.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameMetrics {
    /// Frame index in the input (video frame number or position in the folder).
    pub index: usize,
    pub source: String,
    pub status: RunStatus,
    pub detector_ran: bool,
    pub ms: StageTimes,
    /// Fraction of the vertices (face mesh) or domain pixels (image mesh) with valid depth.
    pub valid_fraction: f64,
    /// Relative residual of the frame's linear system (clip mode: the clip solve's).
    pub relative_residual: f64,
    /// Curvature and roughness, raw and fused (ERRATA 13; flattened into the record).
    #[serde(flatten)]
    pub quality: FrameQuality,
    /// Mean distance (px) between the projected landmark points and the tracked landmarks.
    pub reprojection_px: Option<f64>,
    pub reprojection_raw_px: Option<f64>,
    pub pose: Option<PoseMetrics>,
    /// RMS reprojection error of the rigid face fit (px).
    pub fit_rms_px: Option<f64>,
}

impl FrameMetrics {
    pub fn has_mesh(&self) -> bool {
        matches!(self.status, RunStatus::Solved | RunStatus::Carried)
    }
}

/// Median, 95th percentile and mean of a stage's per-frame times (ms).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Percentiles {
    pub median_ms: f64,
    pub p95_ms: f64,
    pub mean_ms: f64,
}

impl Percentiles {
    /// Nearest-rank percentiles of `values` (zeros when empty).
    pub fn of(mut values: Vec<f64>) -> Self {
        if values.is_empty() {
            return Percentiles {
                median_ms: 0.0,
                p95_ms: 0.0,
                mean_ms: 0.0,
            };
        }
        values.sort_by(f64::total_cmp);
        let rank =
            |q: f64| values[((q * values.len() as f64).ceil() as usize).clamp(1, values.len()) - 1];
        Percentiles {
            median_ms: rank(0.5),
            p95_ms: rank(0.95),
            mean_ms: values.iter().sum::<f64>() / values.len() as f64,
        }
    }
}

/// A figure for the fused surface and the raw one.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FusedAndRaw {
    pub fused: Option<f64>,
    pub raw: Option<f64>,
}

/// The issue #6 quality figures.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct QualitySummary {
    /// Mean over consecutive meshed frames of the RMS vertex motion after the best rigid
    /// alignment (mm), over all mesh vertices. Image mode: vertices are fixed pixels, not
    /// fixed points of the face, so compare the designs on `landmark_jitter_mm`.
    pub vertex_jitter_mm: FusedAndRaw,
    /// The same on the surface at the 468 landmarks (image mode: interpolated at the landmark
    /// pixels; landmarks outside the mesh are left out of the pair).
    pub landmark_jitter_mm: FusedAndRaw,
    /// Mean over meshed frames of the mean landmark reprojection error (px).
    pub reprojection_px: FusedAndRaw,
    /// Consecutive frame pairs measured.
    pub pairs: usize,
    /// `raw / fused` vertex and landmark jitter.
    pub vertex_jitter_reduction: Option<f64>,
    pub landmark_jitter_reduction: Option<f64>,
}

/// Accumulates the quality figures frame by frame (memory: one frame of each surface).
#[derive(Default)]
pub struct QualityMeter {
    vertex_fused: JitterMeter,
    vertex_raw: JitterMeter,
    landmark_fused: JitterMeter,
    landmark_raw: JitterMeter,
    reprojection: (f64, f64, usize),
}

impl QualityMeter {
    /// A meshed frame: its fused and raw surfaces, the same at the landmarks, and the tracked
    /// landmark pixels. Returns the frame's mean reprojection errors (fused, raw).
    pub fn push(
        &mut self,
        k: &Intrinsics,
        fused: &[[f64; 3]],
        raw: &[[f64; 3]],
        fused_landmarks: &[[f64; 3]],
        raw_landmarks: &[[f64; 3]],
        landmarks_px: &[[f64; 2]],
    ) -> (Option<f64>, Option<f64>) {
        self.vertex_fused.push(fused);
        self.vertex_raw.push(raw);
        self.landmark_fused.push(fused_landmarks);
        self.landmark_raw.push(raw_landmarks);
        let f = reprojection_px(k, fused_landmarks, landmarks_px);
        let r = reprojection_px(k, raw_landmarks, landmarks_px);
        if let (Some(f), Some(r)) = (f, r) {
            self.reprojection.0 += f;
            self.reprojection.1 += r;
            self.reprojection.2 += 1;
        }
        (f, r)
    }

    /// A frame without a mesh: no pair spans it.
    pub fn gap(&mut self) {
        for m in [
            &mut self.vertex_fused,
            &mut self.vertex_raw,
            &mut self.landmark_fused,
            &mut self.landmark_raw,
        ] {
            m.gap();
        }
    }

    pub fn summary(&self) -> QualitySummary {
        let mm = |m: &JitterMeter| m.mean().map(|v| v * 1e3);
        let pair = |f: &JitterMeter, r: &JitterMeter| FusedAndRaw {
            fused: mm(f),
            raw: mm(r),
        };
        let ratio = |p: FusedAndRaw| match (p.fused, p.raw) {
            (Some(f), Some(r)) if f > 0.0 => Some(r / f),
            _ => None,
        };
        let vertex = pair(&self.vertex_fused, &self.vertex_raw);
        let landmark = pair(&self.landmark_fused, &self.landmark_raw);
        let (sf, sr, n) = self.reprojection;
        QualitySummary {
            vertex_jitter_mm: vertex,
            landmark_jitter_mm: landmark,
            reprojection_px: FusedAndRaw {
                fused: (n > 0).then(|| sf / n as f64),
                raw: (n > 0).then(|| sr / n as f64),
            },
            pairs: self.vertex_fused.pairs(),
            vertex_jitter_reduction: ratio(vertex),
            landmark_jitter_reduction: ratio(landmark),
        }
    }
}

/// Mean pixel distance between the projections of `points` (NaN = missing) and `pixels`.
fn reprojection_px(k: &Intrinsics, points: &[[f64; 3]], pixels: &[[f64; 2]]) -> Option<f64> {
    let (sum, count) = points
        .iter()
        .zip(pixels)
        .filter(|(p, _)| p.iter().all(|c| c.is_finite()) && p[2] > 0.0)
        .fold((0.0, 0usize), |(s, n), (p, q)| {
            let u = k.project(*p);
            (s + (u[0] - q[0]).hypot(u[1] - q[1]), n + 1)
        });
    (count > 0).then(|| sum / count as f64)
}

/// Totals of a run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunSummary {
    pub frames: usize,
    pub solved: usize,
    pub carried: usize,
    pub no_face: usize,
    pub no_data: usize,
    /// Wall-clock seconds from the first decoded frame to the last frame out.
    pub wall_s: f64,
    /// End-to-end throughput: frames / wall_s.
    pub fps: f64,
    /// Set-up before the first frame: models, operators and factorisation (ms).
    pub setup_ms: f64,
    /// User + system CPU seconds of the process during the frames, and CPU s / wall s (up to
    /// the number of cores).
    pub cpu_s: Option<f64>,
    pub cpu_use: Option<f64>,
    /// Frames on which the face detector ran (the rest were tracked).
    pub detector_runs: usize,
    /// Peak resident set size (VmHWM), MiB.
    pub peak_rss_mib: Option<f64>,
    /// Per stage: median, 95th percentile, mean (ms) over all frames.
    pub stages: std::collections::BTreeMap<&'static str, Percentiles>,
    pub max_relative_residual: f64,
    pub mean_curvature_improvement: f64,
    pub mean_roughness_raw: f64,
    pub mean_roughness: f64,
    pub quality: QualitySummary,
}

impl RunSummary {
    /// Totals of `frames`.
    pub fn of(frames: &[FrameMetrics], quality: QualitySummary, timing: RunTiming) -> Self {
        let count = |s| frames.iter().filter(|f| f.status == s).count();
        let solved: Vec<&FrameMetrics> = frames
            .iter()
            .filter(|f| f.status == RunStatus::Solved)
            .collect();
        let mean = |g: &dyn Fn(&FrameMetrics) -> f64| {
            if solved.is_empty() {
                0.0
            } else {
                solved.iter().map(|f| g(f)).sum::<f64>() / solved.len() as f64
            }
        };
        let stages = StageTimes::NAMES
            .iter()
            .enumerate()
            .map(|(i, &name)| {
                (
                    name,
                    Percentiles::of(frames.iter().map(|f| f.ms.values()[i]).collect()),
                )
            })
            .collect();
        RunSummary {
            frames: frames.len(),
            solved: solved.len(),
            carried: count(RunStatus::Carried),
            no_face: count(RunStatus::NoFace),
            no_data: count(RunStatus::NoData),
            wall_s: timing.wall_s,
            fps: if timing.wall_s > 0.0 {
                frames.len() as f64 / timing.wall_s
            } else {
                0.0
            },
            setup_ms: timing.setup_ms,
            cpu_s: timing.cpu_s,
            cpu_use: timing
                .cpu_s
                .filter(|_| timing.wall_s > 0.0)
                .map(|c| c / timing.wall_s),
            detector_runs: frames.iter().filter(|f| f.detector_ran).count(),
            peak_rss_mib: timing.peak_rss_mib,
            stages,
            max_relative_residual: solved
                .iter()
                .map(|f| f.relative_residual)
                .fold(0.0, f64::max),
            mean_curvature_improvement: mean(&|f| f.quality.curvature_improvement),
            mean_roughness_raw: mean(&|f| f.quality.roughness_raw),
            mean_roughness: mean(&|f| f.quality.roughness),
            quality,
        }
    }
}

/// Whole-run timing and resources.
#[derive(Clone, Copy, Debug, Default)]
pub struct RunTiming {
    pub wall_s: f64,
    pub setup_ms: f64,
    pub cpu_s: Option<f64>,
    pub peak_rss_mib: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_by_nearest_rank() {
        let p = Percentiles::of((1..=100).map(f64::from).collect());
        assert_eq!(p.median_ms, 50.0);
        assert_eq!(p.p95_ms, 95.0);
        assert_eq!(p.mean_ms, 50.5);
        assert_eq!(Percentiles::of(vec![]).p95_ms, 0.0);
    }

    #[test]
    fn reprojection_of_points_on_their_rays_is_zero() {
        let k = Intrinsics::from_fov(64, 48, 60.0).unwrap();
        let pixels = [[10.0, 20.0], [30.5, 7.25]];
        let points = pixels.map(|[u, v]| k.backproject(u, v, 0.7));
        assert!(reprojection_px(&k, &points, &pixels).unwrap() < 1e-9);
        let moved = [[11.0, 20.0], [30.5, 9.25]];
        let e = reprojection_px(&k, &points, &moved).unwrap();
        assert!((e - 1.5).abs() < 1e-9);
        assert_eq!(reprojection_px(&k, &[[f64::NAN; 3]], &[[0.0; 2]]), None);
    }
}
