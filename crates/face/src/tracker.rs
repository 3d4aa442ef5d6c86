//! Video tracking (MediaPipe `face_landmark_front_cpu` with `max_num_faces = 1`): the next
//! frame's ROI comes from the current landmarks; the detector runs only on the first frame,
//! when the face presence drops below the threshold, or when the face is lost. When the iris
//! network is loaded ([`FaceMesh::iris`]) each face also gets its eyes.

use image::RgbImage;

use crate::face::points_bbox;
use crate::landmarker::PRESENCE_THRESHOLD;
use crate::{Face, FaceError, FaceMesh, Roi};

/// What happened on one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackStep {
    /// The tracked face, or `None` when no face was found.
    pub face: Option<Face>,
    /// Whether the detector ran on this frame.
    pub detector_ran: bool,
}

/// Single-face tracker over a frame sequence.
#[derive(Clone, Debug)]
pub struct FaceTracker {
    pub mesh: FaceMesh,
    roi: Option<Roi>,
    /// Frames processed.
    pub frames: usize,
    /// Frames on which the detector ran.
    pub detector_runs: usize,
}

impl FaceTracker {
    /// A tracker with no face yet.
    pub fn new(mesh: FaceMesh) -> Self {
        FaceTracker {
            mesh,
            roi: None,
            frames: 0,
            detector_runs: 0,
        }
    }

    /// Forgets the current face (e.g. at a shot cut): the next frame runs the detector.
    pub fn reset(&mut self) {
        self.roi = None;
    }

    /// Processes the next frame.
    pub fn track(&mut self, frame: &RgbImage) -> Result<TrackStep, FaceError> {
        self.frames += 1;
        if let Some(roi) = self.roi {
            let landmarks = self.mesh.landmarker.landmarks(frame, &roi)?;
            if landmarks.presence >= PRESENCE_THRESHOLD {
                self.roi = Roi::from_landmarks(&landmarks.mediapipe_points());
                let eyes = self.mesh.eyes(frame, &landmarks)?;
                let face = Face {
                    score: landmarks.presence,
                    bbox: points_bbox(&landmarks.points),
                    detection: None,
                    landmarks,
                    eyes,
                };
                return Ok(TrackStep {
                    face: Some(face),
                    detector_ran: false,
                });
            }
        }
        self.detector_runs += 1;
        let face = self.mesh.process(frame)?.into_iter().next();
        self.roi = face
            .as_ref()
            .and_then(|f| Roi::from_landmarks(&f.landmarks.mediapipe_points()));
        Ok(TrackStep {
            face,
            detector_ran: true,
        })
    }
}
