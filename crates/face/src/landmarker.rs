//! Landmarks of one face in a frame: crop the rotated ROI, run FaceMesh, project back
//! (MediaPipe `face_landmark_cpu` + `LandmarkProjectionCalculator`).

use std::path::Path;

use image::RgbImage;

use crate::crop::crop_roi;
use crate::{FaceError, LandmarkNetwork, Roi, LANDMARK_INPUT};

/// Face presence below which MediaPipe drops a tracked face (`min_tracking_confidence`).
pub const PRESENCE_THRESHOLD: f32 = 0.5;

/// 468 landmarks of one face in frame pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameLandmarks {
    /// `(x, y, z)` per landmark in frame pixels, visage convention (centre of pixel `(i, j)` at
    /// `(i, j)`; MediaPipe's normalised × size minus ½). `z` is relative depth with the scale
    /// of `x` (MediaPipe: normalised by the ROI width), negative towards the camera. Not metric:
    /// see [`crate::face_geometry`] (ERRATA 8).
    pub points: Vec<[f32; 3]>,
    /// Face presence `sigmoid(logit)` ∈ [0, 1].
    pub presence: f32,
    /// The ROI the network saw.
    pub roi: Roi,
}

impl FrameLandmarks {
    /// The points in MediaPipe's pixel convention (pixel `(i, j)` covers `[i, i+1)×[j, j+1)`).
    pub fn mediapipe_points(&self) -> Vec<[f32; 3]> {
        self.points
            .iter()
            .map(|p| [p[0] + 0.5, p[1] + 0.5, p[2]])
            .collect()
    }
}

/// The landmark stage: network plus crop buffer, allocation-free per call except the output.
#[derive(Clone, Debug)]
pub struct FaceLandmarker {
    net: LandmarkNetwork,
}

impl FaceLandmarker {
    /// Loads and verifies `face_landmark.tflite` from the model directory.
    pub fn load(models: &Path) -> Result<Self, FaceError> {
        Ok(FaceLandmarker {
            net: LandmarkNetwork::load(models)?,
        })
    }

    /// Wraps an already compiled network.
    pub fn new(net: LandmarkNetwork) -> Self {
        FaceLandmarker { net }
    }

    /// Landmarks inside `roi` (MediaPipe pixel convention) of `image`.
    pub fn landmarks(&mut self, image: &RgbImage, roi: &Roi) -> Result<FrameLandmarks, FaceError> {
        if image.width() == 0 || image.height() == 0 {
            return Err(FaceError::Image {
                reason: format!("empty image {}×{}", image.width(), image.height()),
            });
        }
        if !(roi.size.is_finite()
            && roi.size > 0.0
            && roi.center.iter().all(|c| c.is_finite())
            && roi.rotation.is_finite())
        {
            return Err(FaceError::Image {
                reason: format!("degenerate region of interest {roi:?}"),
            });
        }
        crop_roi(image, roi, LANDMARK_INPUT, self.net.input_mut());
        let raw = self.net.run();
        let inv = 1.0 / LANDMARK_INPUT as f32;
        let points = raw
            .points
            .iter()
            .map(|p| {
                let q = roi.to_frame(p[0] * inv, p[1] * inv);
                [q[0] - 0.5, q[1] - 0.5, p[2] * inv * roi.size]
            })
            .collect();
        Ok(FrameLandmarks {
            points,
            presence: raw.presence(),
            roi: *roi,
        })
    }
}
