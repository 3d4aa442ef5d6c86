//! Single images: every face the detector finds, each with its landmarks (MediaPipe
//! `solutions.face_mesh` with `static_image_mode=True`, any number of faces).

use std::path::Path;

use image::RgbImage;

use crate::landmarker::PRESENCE_THRESHOLD;
use crate::{
    Eyes, Face, FaceDetector, FaceError, FaceLandmarker, FrameLandmarks, IrisLandmarker, Roi,
};

/// Detector + landmarker (+ iris landmarker, optional) for still images.
#[derive(Clone, Debug)]
pub struct FaceMesh {
    pub detector: FaceDetector,
    pub landmarker: FaceLandmarker,
    /// The eye stage; `None` skips the eyes (every [`Face::eyes`] is then `None`).
    pub iris: Option<IrisLandmarker>,
}

impl FaceMesh {
    /// Loads the networks (verified) from the model directory; the iris network only if its
    /// file is there (without it faces have no eyes, everything else works).
    pub fn load(models: &Path) -> Result<Self, FaceError> {
        Ok(FaceMesh {
            detector: FaceDetector::load(models)?,
            landmarker: FaceLandmarker::load(models)?,
            iris: IrisLandmarker::load_if_present(models)?,
        })
    }

    /// The eyes of a face with these landmarks, if the iris network is loaded.
    pub fn eyes(
        &mut self,
        image: &RgbImage,
        landmarks: &FrameLandmarks,
    ) -> Result<Option<Eyes>, FaceError> {
        self.iris
            .as_mut()
            .map(|iris| iris.eyes(image, &landmarks.points))
            .transpose()
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
            let eyes = self.eyes(image, &landmarks)?;
            faces.push(Face {
                score: det.score,
                bbox: [b[0] - 0.5, b[1] - 0.5, b[2], b[3]],
                detection: Some(det),
                landmarks,
                eyes,
            });
        }
        Ok(faces)
    }
}
