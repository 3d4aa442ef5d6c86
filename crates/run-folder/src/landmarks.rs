//! The `landmarks.json` schema of `visage landmarks` and `visage run`:
//! `{"frames": [LandmarksFrame, …]}`, one record per frame, every face with its 468 landmarks
//! (frame pixels; z relative, with the scale of x) and, when the metric fit succeeded, its
//! head pose, and, for the face a mesh was made of, the fused surface's 468 landmark points
//! projected into the frame (`fused_landmarks`, the same pixel convention), so the result can
//! be measured against the tracked points. Values are rounded to what the networks resolve
//! (0.001 px, 0.01°).

use serde::Serialize;
use visage_camera::Intrinsics;
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
    /// The fused surface's 468 landmark points projected into the frame, `[u, v]` pixels
    /// (when the face was meshed; `visage run`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fused_landmarks: Option<Vec<[f64; 2]>>,
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
            fused_landmarks: None,
        }
    }
}

impl LandmarksFrame {
    /// Records the fused surface's landmark points (camera coordinates, metres) projected
    /// with `k` on the frame's meshed face (the first). Points that cannot be projected (the
    /// image mesh's landmarks outside its domain) are NaN and written as `null`.
    pub fn set_fused(&mut self, k: &Intrinsics, fused_landmarks: &[[f64; 3]]) {
        let r = |v: f64| (v * 1000.0).round() / 1000.0;
        if let Some(face) = self.faces.first_mut() {
            face.fused_landmarks = Some(
                fused_landmarks
                    .iter()
                    .map(|&p| {
                        if p[2] > 0.0 {
                            k.project(p).map(r)
                        } else {
                            [f64::NAN; 2]
                        }
                    })
                    .collect(),
            );
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
