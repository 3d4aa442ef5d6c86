//! Landmarks without the rest of the pipeline (`visage landmarks`): per frame, the 468
//! FaceMesh landmarks of the largest face, tracked (the detector runs only when the face is
//! lost), or of every face (both detectors, near and far faces, on every frame), each with
//! its metric face fit.

use std::path::Path;

use visage_camera::Intrinsics;
use visage_face::{
    fit_face_geometry, CanonicalMesh, DetectorUse, Face, FaceGeometry, FaceMesh, FaceTracker,
};
use visage_run_folder::{FaceRecord, LandmarksFrame};
use visage_video::Frame;

use crate::Error;

/// Reads the faces of frames, one sequence (or still image) at a time.
pub struct LandmarkReader {
    tracker: FaceTracker,
    canonical: CanonicalMesh,
    every_face: bool,
}

/// One frame's faces: the landmarks records, the metric fits of the faces that have one, and
/// what the user should know (a frame without a face, a face without a fit).
pub struct FrameFaces {
    pub record: LandmarksFrame,
    pub geometries: Vec<FaceGeometry>,
    pub warnings: Vec<String>,
}

impl LandmarkReader {
    /// The reader with the networks in `models`; `every_face` reports every face of every frame
    /// instead of tracking the largest.
    ///
    /// # Errors
    /// Missing or corrupt model files.
    pub fn load(models: &Path, every_face: bool) -> Result<LandmarkReader, Error> {
        Ok(LandmarkReader {
            tracker: FaceTracker::new(FaceMesh::load(models)?),
            canonical: CanonicalMesh::load(models)?,
            every_face,
        })
    }

    /// The canonical face the metric fits are of.
    pub fn canonical(&self) -> &CanonicalMesh {
        &self.canonical
    }

    /// Starts a new sequence: the track forgets the previous one.
    pub fn start(&mut self) {
        self.tracker.reset();
        // Every face: both detectors, near and far faces merged.
        self.tracker.mesh.detectors = if self.every_face {
            DetectorUse::Both
        } else {
            DetectorUse::FallBack
        };
    }

    /// The faces of `frame` seen by the camera `k`; a `still` image reports every face.
    ///
    /// # Errors
    /// A network failure.
    pub fn read(&mut self, frame: Frame, k: &Intrinsics, still: bool) -> Result<FrameFaces, Error> {
        let faces: Vec<Face> = if still || self.every_face {
            self.tracker.mesh.process(&frame.image)?
        } else {
            self.tracker.track(&frame.image)?.face.into_iter().collect()
        };
        let mut warnings = Vec::new();
        if faces.is_empty() {
            warnings.push(format!("{}: no face found", frame.source));
        }
        let (mut records, mut geometries) = (Vec::new(), Vec::new());
        for face in &faces {
            match fit_face_geometry(&self.canonical, &face.landmarks.points, k) {
                Ok(g) => {
                    records.push(FaceRecord::new(face, Some(&g)));
                    geometries.push(g);
                }
                Err(e) => {
                    warnings.push(format!("{}: no metric fit: {e}", frame.source));
                    records.push(FaceRecord::new(face, None));
                }
            }
        }
        let (width, height) = frame.image.dimensions();
        Ok(FrameFaces {
            record: LandmarksFrame {
                source: frame.source,
                index: frame.index,
                width,
                height,
                faces: records,
            },
            geometries,
            warnings,
        })
    }

    /// Frames tracked so far and the frames of them the detector ran on.
    pub fn tracking(&self) -> (usize, usize) {
        (self.tracker.frames, self.tracker.detector_runs)
    }
}
