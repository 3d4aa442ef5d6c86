//! Landmarks of one face in a frame: crop the rotated ROI, run FaceMesh or the attention face
//! mesh, project back (MediaPipe `face_landmark_cpu` + `LandmarkProjectionCalculator`; with
//! the attention mesh, `refine_landmarks=True`'s lips, eyes and irises too).

use std::path::Path;

use image::RgbImage;

use crate::attention_network::{LEFT_EYE_MESH_INDICES, RIGHT_EYE_MESH_INDICES};
use crate::crop::crop_roi;
use crate::{
    AttentionNetwork, EyeLandmarks, Eyes, FaceError, LandmarkNetwork, Roi, LANDMARK_INPUT,
    NUM_IRIS_POINTS, NUM_LANDMARKS,
};

/// Face presence below which MediaPipe drops a tracked face (`min_tracking_confidence`).
pub const PRESENCE_THRESHOLD: f32 = 0.5;

/// 468 landmarks of one face in frame pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameLandmarks {
    /// `(x, y, z)` per landmark in frame pixels, visage convention (centre of pixel `(i, j)` at
    /// `(i, j)`; MediaPipe's normalised × size minus ½). `z` is relative depth with the scale
    /// of `x` (MediaPipe: normalised by the ROI width), negative towards the camera. Not metric:
    /// see [`crate::face_geometry`] (ERRATA 8). From the attention face mesh, the lips' and
    /// eyes' points are its refined ones (MediaPipe's `refine_landmarks`).
    pub points: Vec<[f32; 3]>,
    /// Face presence `sigmoid(logit)` ∈ [0, 1].
    pub presence: f32,
    /// The ROI the network saw.
    pub roi: Roi,
    /// The eyes' contours and irises, when the network gives them (the attention face mesh).
    pub eyes: Option<Eyes>,
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

/// The network behind [`FaceLandmarker`].
#[derive(Clone, Debug)]
enum Network {
    /// FaceMesh's 468 points (`face_landmark.tflite`).
    Mesh(LandmarkNetwork),
    /// The attention face mesh: the 468 points with refined lips and eyes, and the irises.
    Attention(AttentionNetwork),
}

/// The landmark stage: network plus crop buffer, allocation-free per call except the output.
#[derive(Clone, Debug)]
pub struct FaceLandmarker {
    net: Network,
}

impl FaceLandmarker {
    /// Loads and verifies `face_landmark.tflite` from the model directory.
    pub fn load(models: &Path) -> Result<Self, FaceError> {
        Ok(FaceLandmarker::new(LandmarkNetwork::load(models)?))
    }

    /// Loads and verifies the attention face mesh (`face_landmark_with_attention.tflite`).
    pub fn load_attention(models: &Path) -> Result<Self, FaceError> {
        Ok(FaceLandmarker::with_attention(AttentionNetwork::load(
            models,
        )?))
    }

    /// Wraps an already compiled network.
    pub fn new(net: LandmarkNetwork) -> Self {
        FaceLandmarker {
            net: Network::Mesh(net),
        }
    }

    /// Wraps an already compiled attention face mesh.
    pub fn with_attention(net: AttentionNetwork) -> Self {
        FaceLandmarker {
            net: Network::Attention(net),
        }
    }

    /// Whether the landmarks come with the eyes (the attention face mesh).
    pub fn gives_eyes(&self) -> bool {
        matches!(self.net, Network::Attention(_))
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
        let inv = 1.0 / LANDMARK_INPUT as f32;
        let to_frame = |p: [f32; 3]| {
            let q = roi.to_frame(p[0] * inv, p[1] * inv);
            [q[0] - 0.5, q[1] - 0.5, p[2] * inv * roi.size]
        };
        match &mut self.net {
            Network::Mesh(net) => {
                crop_roi(image, roi, LANDMARK_INPUT, net.input_mut());
                let raw = net.run();
                Ok(FrameLandmarks {
                    points: raw.points.iter().map(|&p| to_frame(p)).collect(),
                    presence: raw.presence(),
                    roi: *roi,
                    eyes: None,
                })
            }
            Network::Attention(net) => {
                crop_roi(image, roi, LANDMARK_INPUT, net.input_mut());
                let raw = net.run();
                let mut refined = raw.refined();
                let irises = refined.split_off(NUM_LANDMARKS);
                let points: Vec<[f32; 3]> = refined.into_iter().map(to_frame).collect();
                let irises: Vec<[f32; 3]> = irises.into_iter().map(to_frame).collect();
                let eye = |indices: &[usize], iris: &[[f32; 3]], nose_first: bool| {
                    let mut iris: [[f32; 3]; NUM_IRIS_POINTS] = std::array::from_fn(|k| iris[k]);
                    if !nose_first {
                        iris.swap(1, 3);
                    }
                    EyeLandmarks {
                        iris,
                        contour: indices.iter().map(|&i| points[i]).collect(),
                        crop: None,
                    }
                };
                // The network's rim points run image right, up, image left, down for both
                // eyes; `EyeLandmarks` wants the nose side first, which is image right for the
                // subject's right eye (image left) and image left for the other.
                let eyes = Eyes {
                    right: eye(&RIGHT_EYE_MESH_INDICES, &irises[..NUM_IRIS_POINTS], true),
                    left: eye(&LEFT_EYE_MESH_INDICES, &irises[NUM_IRIS_POINTS..], false),
                };
                Ok(FrameLandmarks {
                    points,
                    presence: raw.presence(),
                    roi: *roi,
                    eyes: Some(eyes),
                })
            }
        }
    }
}
