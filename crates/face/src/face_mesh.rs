//! Single images: every face the detector finds, each with its landmarks (MediaPipe
//! `solutions.face_mesh` with `static_image_mode=True`, any number of faces).

use std::path::Path;

use image::RgbImage;

use crate::landmarker::PRESENCE_THRESHOLD;
use crate::nms::{weighted_nms, NMS_IOU_THRESHOLD};
use crate::{
    Detection, Eyes, Face, FaceDetector, FaceError, FaceLandmarker, FrameLandmarks, IrisLandmarker,
    Roi,
};

/// The tile side (pixels) the full-range detector also looks at when the whole frame shows
/// no face: faces from about 40 px wide ([`FaceDetector::detect_tiled`]).
pub const FULL_RANGE_TILE: u32 = 640;

/// Which detectors look for faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DetectorUse {
    /// The short-range detector, and the full-range one (tiled) when it finds nothing.
    #[default]
    FallBack,
    /// Both, their faces merged: every face in view, near and far.
    Both,
}

/// Detectors + landmarker (the attention face mesh, or FaceMesh's plain network with the iris
/// network, optional) for still images.
#[derive(Clone, Debug)]
pub struct FaceMesh {
    /// The short-range detector (faces within about 2 m).
    pub detector: FaceDetector,
    /// The full-range detector, when its model file is there.
    pub full_range: Option<FaceDetector>,
    /// Which detectors [`FaceMesh::process`] runs.
    pub detectors: DetectorUse,
    pub landmarker: FaceLandmarker,
    /// The iris network, for a landmarker that gives no eyes of its own; `None` there skips
    /// the eyes (every [`Face::eyes`] is then `None`).
    pub iris: Option<IrisLandmarker>,
}

impl FaceMesh {
    /// Loads the networks (verified) from the model directory: the detectors, FaceMesh's
    /// 468-point network (MediaPipe's `refine_landmarks=False`) and, if its file is there, the
    /// iris network for the eyes (MediaPipe Iris on a crop of each eye; without it faces have
    /// no eyes, everything else works). What the pipeline runs.
    pub fn load(models: &Path) -> Result<Self, FaceError> {
        Ok(FaceMesh {
            detector: FaceDetector::load(models)?,
            full_range: FaceDetector::load_full_range_if_present(models)?,
            detectors: DetectorUse::default(),
            landmarker: FaceLandmarker::load(models)?,
            iris: IrisLandmarker::load_if_present(models)?,
        })
    }

    /// Loads the detectors and the attention face mesh, whose landmarks come with refined lips
    /// and eyes and with both irises in one network run (MediaPipe's `refine_landmarks=True`).
    pub fn load_attention(models: &Path) -> Result<Self, FaceError> {
        Ok(FaceMesh {
            detector: FaceDetector::load(models)?,
            full_range: FaceDetector::load_full_range_if_present(models)?,
            detectors: DetectorUse::default(),
            landmarker: FaceLandmarker::load_attention(models)?,
            iris: None,
        })
    }

    /// The eyes of a face with these landmarks: those the attention face mesh gave with them,
    /// or the iris network's when it is loaded.
    pub fn eyes(
        &mut self,
        image: &RgbImage,
        landmarks: &FrameLandmarks,
    ) -> Result<Option<Eyes>, FaceError> {
        if let Some(eyes) = &landmarks.eyes {
            return Ok(Some(eyes.clone()));
        }
        self.iris
            .as_mut()
            .map(|iris| iris.eyes(image, &landmarks.points))
            .transpose()
    }

    /// The detections of `image` by the detectors [`FaceMesh::detectors`] chooses, highest
    /// score first.
    pub fn detect(&mut self, image: &RgbImage) -> Result<Vec<Detection>, FaceError> {
        let mut detections = self.detector.detect(image)?;
        let Some(full) = self.full_range.as_mut() else {
            return Ok(detections);
        };
        match self.detectors {
            DetectorUse::FallBack if !detections.is_empty() => Ok(detections),
            DetectorUse::FallBack => full.detect_tiled(image, FULL_RANGE_TILE),
            DetectorUse::Both => {
                detections.extend(full.detect_tiled(image, FULL_RANGE_TILE)?);
                Ok(weighted_nms(detections, NMS_IOU_THRESHOLD))
            }
        }
    }

    /// All faces of `image`, highest detection score first; faces whose landmark presence is
    /// below [`PRESENCE_THRESHOLD`] are dropped. No face → empty list.
    pub fn process(&mut self, image: &RgbImage) -> Result<Vec<Face>, FaceError> {
        let mut faces = Vec::new();
        for det in self.detect(image)? {
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
