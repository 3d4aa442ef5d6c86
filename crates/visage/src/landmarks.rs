//! The `landmarks.json` schema of `visage landmarks` and `visage run`:
//! `{"frames": [LandmarksFrame, …]}`, one record per frame, every face with its 468 landmarks
//! (frame pixels; z relative, with the scale of x) and, when the metric fit succeeded, its
//! head pose. Values are rounded to what the networks resolve (0.001 px, 0.01°).

use serde::Serialize;
use visage_face::{Face, FaceGeometry};

use crate::metrics::PoseMetrics;

/// One frame of `landmarks.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LandmarksFrame {
    /// The frame's source (image file, or `video.mp4:INDEX`).
    pub source: String,
    /// Frame index in the input.
    pub index: usize,
    pub width: u32,
    pub height: u32,
    pub faces: Vec<FaceRecord>,
}

/// One face of a frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FaceRecord {
    /// Detection score (a tracked face: the landmark network's presence).
    pub score: f64,
    /// Face box `[x, y, w, h]`, frame pixels.
    #[serde(rename = "box")]
    pub bbox: [f64; 4],
    /// The landmark network's face presence.
    pub presence: f64,
    /// 468 × `[x, y, z]`, frame pixels.
    pub landmarks: Vec<[f64; 3]>,
    /// The metric head pose, when the fit succeeded.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pose: Option<PoseRecord>,
}

/// Metric head pose `X_cam = R · X_canonical + t` (camera coordinates, metres), its Z-Y-X
/// Euler angles and the fit's reprojection error.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseRecord {
    pub rotation: [[f64; 3]; 3],
    pub translation_m: [f64; 3],
    pub yaw_deg: f64,
    pub pitch_deg: f64,
    pub roll_deg: f64,
    pub reprojection_rms_px: f64,
}

impl FaceRecord {
    /// The record of a face, with the pose of its metric fit if there is one.
    pub fn new(face: &Face, fit: Option<&FaceGeometry>) -> Self {
        let r = |v: f32| (v as f64 * 1000.0).round() / 1000.0;
        FaceRecord {
            score: r(face.score),
            bbox: face.bbox.map(r),
            presence: r(face.landmarks.presence),
            landmarks: face.landmarks.points.iter().map(|p| p.map(r)).collect(),
            pose: fit.map(PoseRecord::new),
        }
    }
}

impl PoseRecord {
    /// The record of a metric face fit.
    pub fn new(g: &FaceGeometry) -> Self {
        let p = PoseMetrics::of(&g.pose);
        let deg = |v: f64| (v * 100.0).round() / 100.0;
        PoseRecord {
            rotation: p.rotation,
            translation_m: p.translation_m,
            yaw_deg: deg(p.yaw_deg),
            pitch_deg: deg(p.pitch_deg),
            roll_deg: deg(p.roll_deg),
            reprojection_rms_px: (g.rms_px * 1000.0).round() / 1000.0,
        }
    }
}
