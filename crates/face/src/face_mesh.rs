//! Single images: every face the detector finds, each with its landmarks (MediaPipe
//! `solutions.face_mesh` with `static_image_mode=True`, any number of faces).

use std::path::Path;

use image::RgbImage;

use crate::landmarker::PRESENCE_THRESHOLD;
use crate::{Face, FaceDetector, FaceError, FaceLandmarker, Roi};

/// Detector + landmarker for still images.
#[derive(Clone, Debug)]
pub struct FaceMesh {
    pub detector: FaceDetector,
    pub landmarker: FaceLandmarker,
}

impl FaceMesh {
    /// Loads both networks (verified) from the model directory.
    pub fn load(models: &Path) -> Result<Self, FaceError> {
        Ok(FaceMesh {
            detector: FaceDetector::load(models)?,
            landmarker: FaceLandmarker::load(models)?,
        })
    }

    /// All faces of `image`, highest detection score first; faces whose landmark presence is
    /// below [`PRESENCE_THRESHOLD`] are dropped. No face → empty list.
    pub fn process(&mut self, image: &RgbImage) -> Result<Vec<Face>, FaceError> {
        let mut faces = Vec::new();
        for det in self.detector.detect(image)? {
            let roi = Roi::from_detection(&det);
            let landmarks = self.landmarker.landmarks(image, &roi)?;
            if landmarks.presence < PRESENCE_THRESHOLD {
                continue;
            }
            let b = det.bbox();
            faces.push(Face {
                score: det.score,
                bbox: [b[0] - 0.5, b[1] - 0.5, b[2], b[3]],
                detection: Some(det),
                landmarks,
            });
        }
        Ok(faces)
    }
}
