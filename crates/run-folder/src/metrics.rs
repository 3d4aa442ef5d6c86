//! The metrics schema of `visage run`, `visage bench` and `visage fuse` (`metrics.json`): per
//! frame the status, stage times, solver and surface figures and head pose; per run the
//! throughput, CPU use, peak memory and the quality figures (jitter with the rigid head motion
//! removed, landmark reprojection error), each for the fused and the raw surface.

use serde::Serialize;
use visage_camera::{Intrinsics, RigidTransform};
use visage_fem::{ClipReport, SurfaceQuality};

/// Outcome of one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameStatus {
    /// Fused from its own depth; a mesh was made.
    Solved,
    /// No valid depth: the previous surface was carried over (a mesh was made).
    Carried,
    /// No face found: no mesh; the fusion's history restarts at the next face.
    NoFace,
    /// No depth and no previous surface: no mesh.
    NoData,
}

impl From<visage_fusion::FrameStatus> for FrameStatus {
    fn from(s: visage_fusion::FrameStatus) -> Self {
        match s {
            visage_fusion::FrameStatus::Solved => FrameStatus::Solved,
            visage_fusion::FrameStatus::Carried => FrameStatus::Carried,
            visage_fusion::FrameStatus::NoData => FrameStatus::NoData,
        }
    }
}

/// Mean |H| and roughness of a frame's raw and fused surfaces (ERRATA 13).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FrameQuality {
    /// Mean |H| (1/m) of the raw surface on the mesh.
    pub mean_abs_h_raw: f64,
    /// Mean |H| (1/m) after fusion.
    pub mean_abs_h: f64,
    /// `mean_abs_h_raw / mean_abs_h` (0 when the fused surface is flat).
    pub curvature_improvement: f64,
    /// Roughness (radians, mean normal deviation from the one-ring) of the raw surface.
    pub roughness_raw: f64,
    /// Roughness (radians) after fusion.
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

/// Wall-clock milliseconds of each stage for one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StageTimes {
    /// Reading/decoding the frame (FFmpeg pipe or image file; a depth folder's PNG).
    pub decode: f64,
    /// Face tracking: landmark network, and the detector when the track was lost.
    pub track: f64,
    /// Metric face fit (pose + metric landmarks).
    pub fit: f64,
    /// Depth map: a depth folder's or recording's PNG read (edges masked, registered), a depth
    /// network's inference and alignment, or the image mesh's face rasterisation (the face
    /// mesh on the face fit's surface intersects that surface inside the fusion: 0).
    pub depth: f64,
    /// Fusion: right-hand side, solve, curvature and roughness figures (clip mode: plus the
    /// frame's share of the clip solve).
    pub fuse: f64,
    /// Writing the mesh(es) and the landmarks record.
    pub write: f64,
    /// The keypoint check of the head's motion (with keypoints on; 0 otherwise).
    pub keypoints: f64,
}

impl StageTimes {
    pub const NAMES: [&'static str; 7] = [
        "decode",
        "track",
        "fit",
        "depth",
        "fuse",
        "write",
        "keypoints",
    ];

    pub fn values(&self) -> [f64; 7] {
        [
            self.decode,
            self.track,
            self.fit,
            self.depth,
            self.fuse,
            self.write,
            self.keypoints,
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
    /// Seconds since the input's first frame (the video's timestamp, or index / frame rate).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_s: Option<f64>,
    pub status: FrameStatus,
    /// Whether the face detector ran (video runs; the rest of the frames were tracked).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub detector_ran: Option<bool>,
    /// When the detector ran: the faces it found (the tracked one among them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub faces_seen: Option<usize>,
    /// The frame starts a new shot (a cut, or the face jumped): the tracker looked for the
    /// face afresh and the temporal terms restarted here.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub cut: bool,
    /// Why a face that was found got no mesh: its metric fit failed (e.g. intrinsics so wide
    /// that the fit put the face behind the camera).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit_error: Option<String>,
    pub ms: StageTimes,
    /// Fraction of the vertices (face mesh) or domain pixels (image mesh) with valid depth.
    pub valid_fraction: f64,
    /// Relative residual of the frame's linear system (clip mode: the clip solve's).
    pub relative_residual: f64,
    /// Curvature and roughness, raw and fused (ERRATA 13; flattened into the record).
    #[serde(flatten)]
    pub quality: FrameQuality,
    /// Mean distance (px) between the projected landmark points and the tracked landmarks.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reprojection_px: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reprojection_raw_px: Option<f64>,
    /// Head pose of the metric face fit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pose: Option<PoseMetrics>,
    /// RMS reprojection error of the rigid face fit (px).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit_rms_px: Option<f64>,
    /// Mean distance (px) of the morphable-model fit's landmarks from the tracked ones.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model_fit_px: Option<f64>,
    /// Conjugate-gradient iterations of the fairing (with `--fair`; the fused quality figures
    /// are then the faired surface's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fairing_iterations: Option<usize>,
    /// SIFT keypoints' check of the head's motion since the previous frame (with keypoints
    /// on, from a face's second frame).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub keypoint_motion: Option<KeypointMotionMetrics>,
    /// A depth network's output brought to the metric face (with `--depth MODEL.onnx`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth_alignment: Option<DepthAlignmentMetrics>,
}

/// One frame's alignment of a depth network's output to the fitted face (`metrics.json`):
/// `y = scale · output + shift` in the output's space (depth, or inverse depth for inverse
/// depth and disparity outputs).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DepthAlignmentMetrics {
    /// Face pixels compared, and of those the ones that agree with the fit.
    pub samples: usize,
    pub inliers: usize,
    /// RMS depth difference from the fitted face over the inliers, millimetres.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_mm: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shift: Option<f64>,
    /// Why the output was not used for this frame (it then has no depth: the surface is
    /// carried).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

impl DepthAlignmentMetrics {
    pub fn aligned(fit: &visage_depth::Alignment) -> Self {
        DepthAlignmentMetrics {
            samples: fit.samples,
            inliers: fit.inliers,
            residual_mm: Some(fit.residual_m * 1e3),
            scale: Some(fit.scale),
            shift: Some(fit.shift),
            failure: None,
        }
    }

    pub fn failed(failure: &visage_depth::AlignmentFailure) -> Self {
        let (samples, inliers) = match failure {
            visage_depth::AlignmentFailure::TooFewSamples { found, .. } => (*found, 0),
            visage_depth::AlignmentFailure::NoConsensus { inliers, samples } => {
                (*samples, *inliers)
            }
            visage_depth::AlignmentFailure::Inverted { .. } => (0, 0),
        };
        DepthAlignmentMetrics {
            samples,
            inliers,
            residual_mm: None,
            scale: None,
            shift: None,
            failure: Some(failure.to_string()),
        }
    }
}

/// A depth network's alignment over a run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DepthAlignmentSummary {
    /// Frames the network ran on, and of those the ones whose output could not be aligned.
    pub frames: usize,
    pub failed: usize,
    /// Median and 95th percentile of the per-frame residual (mm) over the aligned frames.
    pub median_residual_mm: f64,
    pub p95_residual_mm: f64,
    /// Median fraction of the compared face pixels that agree with the fit.
    pub median_inlier_fraction: f64,
}

impl DepthAlignmentSummary {
    /// The summary of `frames`' records (`None` when no frame has one).
    pub fn of(frames: &[FrameMetrics]) -> Option<Self> {
        let records: Vec<&DepthAlignmentMetrics> = frames
            .iter()
            .filter_map(|f| f.depth_alignment.as_ref())
            .collect();
        if records.is_empty() {
            return None;
        }
        let residual = Percentiles::of(records.iter().filter_map(|r| r.residual_mm).collect());
        let fraction = Percentiles::of(
            records
                .iter()
                .filter(|r| r.failure.is_none())
                .map(|r| r.inliers as f64 / r.samples.max(1) as f64)
                .collect(),
        );
        Some(DepthAlignmentSummary {
            frames: records.len(),
            failed: records.iter().filter(|r| r.failure.is_some()).count(),
            median_residual_mm: residual.median_ms,
            p95_residual_mm: residual.p95_ms,
            median_inlier_fraction: fraction.median_ms,
        })
    }
}

impl FrameMetrics {
    /// A frame record with nothing measured yet.
    pub fn new(index: usize, source: String, status: FrameStatus) -> Self {
        FrameMetrics {
            index,
            source,
            time_s: None,
            status,
            detector_ran: None,
            faces_seen: None,
            cut: false,
            fit_error: None,
            ms: StageTimes::default(),
            valid_fraction: 0.0,
            relative_residual: 0.0,
            quality: FrameQuality::default(),
            reprojection_px: None,
            reprojection_raw_px: None,
            pose: None,
            fit_rms_px: None,
            model_fit_px: None,
            fairing_iterations: None,
            keypoint_motion: None,
            depth_alignment: None,
        }
    }

    /// Whether the frame has a mesh.
    pub fn has_mesh(&self) -> bool {
        matches!(self.status, FrameStatus::Solved | FrameStatus::Carried)
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

/// One frame's keypoint check of the head's motion since the previous frame (`metrics.json`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct KeypointMotionMetrics {
    /// SIFT keypoints on the fitted face surface in this frame.
    pub keypoints: usize,
    /// Of those, matched with the previous frame's (ratio test, mutual).
    pub matches: usize,
    /// Matches the RANSAC motion explains within the inlier threshold (0: no
    /// estimate).
    pub inliers: usize,
    /// The keypoints' rotation since the previous frame, degrees (`None`: no estimate).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rotation_deg: Option<f64>,
    /// Angle between the keypoints' rotation and the landmark pose's, degrees.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rotation_disagreement_deg: Option<f64>,
    /// Distance between where the two motions take the face's centre, millimetres.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub translation_disagreement_mm: Option<f64>,
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
    /// User + system CPU seconds during the frames, of the process and the decoder it runs
    /// (FFmpeg), and CPU s / wall s (up to the number of cores).
    pub cpu_s: Option<f64>,
    pub cpu_use: Option<f64>,
    /// CPU milliseconds per frame, decoding included (`cpu_s` / frames).
    pub cpu_ms_per_frame: Option<f64>,
    /// Frames on which the face detector ran (the rest were tracked).
    pub detector_runs: usize,
    /// The most faces the detector found in one frame, and the first frame (input index) where
    /// it found that many; one face was tracked.
    pub most_faces_seen: usize,
    pub most_faces_frame: Option<usize>,
    /// Frames (input indices) that start a new shot; the temporal terms restarted there.
    pub cuts: Vec<usize>,
    /// Peak resident set size (VmHWM), MiB.
    pub peak_rss_mib: Option<f64>,
    /// Per stage: median, 95th percentile, mean (ms) over all frames.
    pub stages: std::collections::BTreeMap<&'static str, Percentiles>,
    pub max_relative_residual: f64,
    pub mean_curvature_improvement: f64,
    pub mean_roughness_raw: f64,
    pub mean_roughness: f64,
    pub quality: QualitySummary,
    /// The keypoint check of the head's motion over the run (with keypoints on).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub keypoint_motion: Option<KeypointMotionSummary>,
    /// A depth network's alignment to the fitted face over the run (with a network).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth_alignment: Option<DepthAlignmentSummary>,
}

/// The keypoint check over a run: how often it could estimate the motion and how far that
/// motion was from the landmark pose's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct KeypointMotionSummary {
    /// Frames compared with their predecessor.
    pub frames: usize,
    /// Of those, frames with a motion estimate.
    pub estimated: usize,
    /// Medians per compared frame.
    pub median_keypoints: f64,
    pub median_matches: f64,
    pub median_inliers: f64,
    /// Median and 95th percentile of the disagreement over the estimated frames.
    pub median_rotation_disagreement_deg: f64,
    pub p95_rotation_disagreement_deg: f64,
    pub median_translation_disagreement_mm: f64,
    pub p95_translation_disagreement_mm: f64,
}

impl KeypointMotionSummary {
    /// The summary of `frames`' records (`None` when no frame has one).
    pub fn of(frames: &[FrameMetrics]) -> Option<Self> {
        let records: Vec<&KeypointMotionMetrics> = frames
            .iter()
            .filter_map(|f| f.keypoint_motion.as_ref())
            .collect();
        if records.is_empty() {
            return None;
        }
        let median = |v: Vec<f64>| Percentiles::of(v).median_ms;
        let spread = |v: Vec<f64>| {
            let p = Percentiles::of(v);
            (p.median_ms, p.p95_ms)
        };
        let (rotation, rotation_p95) = spread(
            records
                .iter()
                .filter_map(|r| r.rotation_disagreement_deg)
                .collect(),
        );
        let (translation, translation_p95) = spread(
            records
                .iter()
                .filter_map(|r| r.translation_disagreement_mm)
                .collect(),
        );
        Some(KeypointMotionSummary {
            frames: records.len(),
            estimated: records.iter().filter(|r| r.rotation_deg.is_some()).count(),
            median_keypoints: median(records.iter().map(|r| r.keypoints as f64).collect()),
            median_matches: median(records.iter().map(|r| r.matches as f64).collect()),
            median_inliers: median(records.iter().map(|r| r.inliers as f64).collect()),
            median_rotation_disagreement_deg: rotation,
            p95_rotation_disagreement_deg: rotation_p95,
            median_translation_disagreement_mm: translation,
            p95_translation_disagreement_mm: translation_p95,
        })
    }
}

impl RunSummary {
    /// Totals of `frames`.
    pub fn of(frames: &[FrameMetrics], quality: QualitySummary, timing: RunTiming) -> Self {
        let count = |s| frames.iter().filter(|f| f.status == s).count();
        let solved: Vec<&FrameMetrics> = frames
            .iter()
            .filter(|f| f.status == FrameStatus::Solved)
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
        let most_faces = frames
            .iter()
            .filter_map(|f| f.faces_seen.map(|n| (f.index, n)))
            .fold(None, |best: Option<(usize, usize)>, (i, n)| match best {
                Some(b) if b.1 >= n => Some(b),
                _ => Some((i, n)),
            });
        RunSummary {
            frames: frames.len(),
            solved: solved.len(),
            carried: count(FrameStatus::Carried),
            no_face: count(FrameStatus::NoFace),
            no_data: count(FrameStatus::NoData),
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
            cpu_ms_per_frame: timing
                .cpu_s
                .filter(|_| !frames.is_empty())
                .map(|c| 1e3 * c / frames.len() as f64),
            detector_runs: frames
                .iter()
                .filter(|f| f.detector_ran == Some(true))
                .count(),
            most_faces_seen: most_faces.map_or(0, |f| f.1),
            most_faces_frame: most_faces.map(|f| f.0),
            cuts: frames.iter().filter(|f| f.cut).map(|f| f.index).collect(),
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
            keypoint_motion: KeypointMotionSummary::of(frames),
            depth_alignment: DepthAlignmentSummary::of(frames),
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

/// Size of the mesh of a run.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct MeshSummary {
    /// 0 when no frame was meshed.
    pub vertices: usize,
    pub triangles: usize,
    /// Image-plane mesh of a depth folder: boundary vertices, depth range / mean depth, and
    /// whether (and how many) depth-aware flips were made.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub boundary_vertices: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flatness_ratio: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth_aware_flips: Option<usize>,
}

/// Set-up cost of the solver (a depth folder's run).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SolverSummary {
    /// Stored values of the Cholesky factor.
    pub factor_nnz: usize,
    /// Symbolic + numeric factorisation time (ms), once per sequence.
    pub factor_ms: f64,
    /// Clip mode: the solve over the whole clip, and its time (ms).
    pub clip: Option<ClipReport>,
    pub clip_ms: Option<f64>,
}

/// Whether a run finished.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
    Complete,
    /// Stopped by an error (`Report::error`); the frames before it are listed.
    Failed,
    /// Stopped on request (Ctrl-C, SIGTERM) after a frame; the frames before it are listed.
    Interrupted,
    /// Written when a run starts (with the input, camera and parameters, no frames): a
    /// `metrics.json` that still says so after the run is gone belongs to a killed run.
    Running,
}

/// Everything `metrics.json` holds. `P` is the run's parameters.
#[derive(Clone, Debug, Serialize)]
pub struct Report<P: Serialize> {
    pub status: RunStatus,
    pub error: Option<String>,
    /// The input (video, image folder or image; depth folder).
    pub input: String,
    /// The camera the meshes are in.
    pub intrinsics: Intrinsics,
    pub parameters: P,
    /// Which input frames the run processes (set by the caller that chose them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub selection: Option<crate::FrameSelection>,
    /// A resumed run: where it continued, and what the files kept from before. `frames`
    /// in `metrics.json` lists every frame the files hold (the kept frames' records first,
    /// `ResumePoint::kept_records`); the summary covers every frame this run processed, its
    /// warm-up included.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resumed: Option<crate::ResumePoint>,
    pub mesh: MeshSummary,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub solver: Option<SolverSummary>,
    pub summary: RunSummary,
    pub frames: Vec<FrameMetrics>,
}

/// A figure for the fused surface and the raw one.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FusedAndRaw {
    pub fused: Option<f64>,
    pub raw: Option<f64>,
}

/// The quality figures of a run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct QualitySummary {
    /// Mean over consecutive meshed frames of the RMS vertex motion after the best rigid
    /// alignment (mm), over all mesh vertices. Image mesh: vertices are fixed pixels, not
    /// fixed points of the face, so compare the designs on `landmark_jitter_mm`.
    pub vertex_jitter_mm: FusedAndRaw,
    /// The same on the surface at the 468 landmarks (image mesh: interpolated at the landmark
    /// pixels; landmarks outside the mesh are left out of the pair). None without landmarks
    /// (a depth folder).
    pub landmark_jitter_mm: FusedAndRaw,
    /// Mean over meshed frames of the mean landmark reprojection error (px).
    pub reprojection_px: FusedAndRaw,
    /// RMS over frames and landmarks of the second difference ‖p(t+1) − 2p(t) + p(t−1)‖ (px)
    /// of the fused landmarks projected into the image (`fused`) and of the tracked ones
    /// (`raw`), over runs of consecutive meshed frames.
    pub image_jitter_px: FusedAndRaw,
    /// `raw / fused` image jitter: how much steadier than tracked.
    pub image_jitter_reduction: Option<f64>,
    /// Consecutive frame pairs measured.
    pub pairs: usize,
    /// `raw / fused` vertex and landmark jitter.
    pub vertex_jitter_reduction: Option<f64>,
    pub landmark_jitter_reduction: Option<f64>,
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
}
