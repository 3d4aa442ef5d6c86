//! Video tracking (MediaPipe `face_landmark_front_cpu` with `max_num_faces = 1`): the next
//! frame's ROI comes from the current landmarks; the detector runs only on the first frame,
//! when the face presence drops below the threshold, or when the face is lost. Each face also
//! gets its eyes: the attention face mesh's, or the iris network's when it is loaded
//! ([`FaceMesh::iris`]).

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
    /// When the detector ran: how many faces it found (the tracked one among them).
    pub faces_seen: usize,
}

/// Which face a tracker takes when the detector runs.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum FaceTarget {
    /// The largest face (by box area): the person nearest the camera.
    #[default]
    Largest,
    /// The face that overlaps this box (`[x, y, width, height]`, pixels) most, and after that
    /// the one nearest where the tracked face was last seen; no face when none is near, so
    /// that a track never jumps to another person.
    Near([f32; 4]),
}

impl FaceTarget {
    /// The face `self` takes among `faces`, given the tracked face's last box.
    fn pick(self, faces: Vec<Face>, last: Option<[f32; 4]>) -> Option<Face> {
        match self {
            FaceTarget::Largest => faces
                .into_iter()
                .max_by(|a, b| (a.bbox[2] * a.bbox[3]).total_cmp(&(b.bbox[2] * b.bbox[3]))),
            FaceTarget::Near(first) => {
                let target = last.unwrap_or(first);
                faces
                    .into_iter()
                    .map(|f| (box_proximity(&f.bbox, &target), f))
                    .filter(|(p, _)| *p > 0.0)
                    .max_by(|a, b| a.0.total_cmp(&b.0))
                    .map(|(_, f)| f)
            }
        }
    }
}

/// How near box `a` is to box `b` (`[x, y, w, h]`): 1 + their IoU when they overlap, else
/// a value in [0, 1) that falls with the distance of the centres, 0 at 1.5 widths of `b` and
/// beyond (not near).
pub fn box_proximity(a: &[f32; 4], b: &[f32; 4]) -> f32 {
    let ix = (a[0] + a[2]).min(b[0] + b[2]) - a[0].max(b[0]);
    let iy = (a[1] + a[3]).min(b[1] + b[3]) - a[1].max(b[1]);
    if ix > 0.0 && iy > 0.0 {
        let inter = ix * iy;
        return 1.0 + inter / (a[2] * a[3] + b[2] * b[3] - inter);
    }
    let d = (a[0] + 0.5 * a[2] - b[0] - 0.5 * b[2]).hypot(a[1] + 0.5 * a[3] - b[1] - 0.5 * b[3]);
    (1.0 - d / (1.5 * b[2].max(1.0))).max(0.0)
}

/// Single-face tracker over a frame sequence.
#[derive(Clone, Debug)]
pub struct FaceTracker {
    pub mesh: FaceMesh,
    /// Which face to take when the detector runs.
    pub target: FaceTarget,
    roi: Option<Roi>,
    /// The tracked face's last box.
    last_bbox: Option<[f32; 4]>,
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
            target: FaceTarget::default(),
            roi: None,
            last_bbox: None,
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
                self.last_bbox = Some(face.bbox);
                return Ok(TrackStep {
                    face: Some(face),
                    detector_ran: false,
                    faces_seen: 0,
                });
            }
        }
        self.detector_runs += 1;
        let faces = self.mesh.process(frame)?;
        let faces_seen = faces.len();
        let face = self.target.pick(faces, self.last_bbox);
        self.roi = face
            .as_ref()
            .and_then(|f| Roi::from_landmarks(&f.landmarks.mediapipe_points()));
        if let Some(f) = &face {
            self.last_bbox = Some(f.bbox);
        }
        Ok(TrackStep {
            face,
            detector_ran: true,
            faces_seen,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::box_proximity;

    #[test]
    fn proximity_is_iou_when_boxes_overlap_and_falls_with_distance_otherwise() {
        let b = [100.0, 100.0, 50.0, 50.0];
        assert!((box_proximity(&b, &b) - 2.0).abs() < 1e-6);
        let half = [125.0, 100.0, 50.0, 50.0];
        assert!((box_proximity(&half, &b) - 4.0 / 3.0).abs() < 1e-6);
        let beside = [160.0, 100.0, 50.0, 50.0];
        let far = [300.0, 100.0, 50.0, 50.0];
        let p = box_proximity(&beside, &b);
        assert!(p > 0.0 && p < 1.0, "{p}");
        assert_eq!(box_proximity(&far, &b), 0.0);
    }
}
