//! Eye and iris landmarks of one face in a frame: crop each eye from the face's landmarks, run
//! the iris network, map the points back to the frame (MediaPipe Iris, with the axis-aligned
//! crop of `shared/reference/facemesh`, see [`crate::eye_crop`]).

use std::path::Path;

use image::RgbImage;

use crate::{CropEye, Eye, EyeCrop, FaceError, IrisNetwork, NUM_IRIS_POINTS};

/// Where the lids are in [`EyeLandmarks::contour`] (MediaPipe's eye contour: the lower lid from
/// corner to corner, points 0–8, then the upper lid between the corners, 9–15, then the halos
/// and the brow): the corners, the lower lid's centre and the upper lid's centre.
const CONTOUR_CORNERS: [usize; 2] = [0, 8];
const CONTOUR_LOWER_LID: usize = 4;
const CONTOUR_UPPER_LID: usize = 12;

/// One eye's landmarks in frame pixels, visage convention (centre of pixel `(i, j)` at
/// `(i, j)`).
#[derive(Clone, Debug, PartialEq)]
pub struct EyeLandmarks {
    /// The iris centre, then four points on its rim: towards the nose, up, towards the temple,
    /// down (the right eye's crop is unmirrored, so there "towards the nose" is towards image
    /// right; the left eye's is mirrored, so its rim points are in the same anatomical order). `z` is the network's relative depth scaled like `x`
    /// (frame pixels); its origin is the eye crop's, not the face mesh's.
    pub iris: [[f32; 3]; NUM_IRIS_POINTS],
    /// 71 eye-contour and eyebrow points, in the network's order.
    pub contour: Vec<[f32; 3]>,
    /// The crop the iris network saw; `None` when the eyes came with the face's landmarks
    /// (the attention mesh, [`crate::AttentionNetwork`]).
    pub crop: Option<EyeCrop>,
}

impl EyeLandmarks {
    /// The iris centre `(x, y, z)`.
    pub fn iris_center(&self) -> [f32; 3] {
        self.iris[0]
    }

    /// The iris radius in frame pixels: a quarter of the sum of the horizontal and vertical
    /// rim-to-rim distances (MediaPipe's `iris_to_depth` diameter, halved).
    pub fn iris_radius(&self) -> f32 {
        let d = |a: [f32; 3], b: [f32; 3]| (a[0] - b[0]).hypot(a[1] - b[1]);
        0.25 * (d(self.iris[1], self.iris[3]) + d(self.iris[2], self.iris[4]))
    }

    /// The lids' centres and the eye's corners (frame pixels): upper lid, lower lid, then the
    /// two corners; `None` without a contour.
    pub fn lid_points(&self) -> Option<[[f64; 2]; 4]> {
        let c = &self.contour;
        let p = |i: usize| c.get(i).map(|p| [p[0] as f64, p[1] as f64]);
        Some([
            p(CONTOUR_UPPER_LID)?,
            p(CONTOUR_LOWER_LID)?,
            p(CONTOUR_CORNERS[0])?,
            p(CONTOUR_CORNERS[1])?,
        ])
    }

    fn from_crop(raw: &CropEye, crop: EyeCrop) -> EyeLandmarks {
        EyeLandmarks {
            iris: raw.iris.map(|p| crop.to_frame(p)),
            contour: raw.contour.iter().map(|&p| crop.to_frame(p)).collect(),
            crop: Some(crop),
        }
    }
}

/// Both eyes of a face. `right` is the **subject's** right eye (MediaPipe's "right eye",
/// landmarks 33/133, iris 468–472 of the refined mesh), which is on the **left** of an
/// unmirrored image; `left` is the subject's left eye (362/263, iris 473–477), on the image's
/// right.
#[derive(Clone, Debug, PartialEq)]
pub struct Eyes {
    /// The subject's right eye (image left).
    pub right: EyeLandmarks,
    /// The subject's left eye (image right).
    pub left: EyeLandmarks,
}

impl Eyes {
    /// The landmarks of `eye`.
    pub fn get(&self, eye: Eye) -> &EyeLandmarks {
        match eye {
            Eye::Right => &self.right,
            Eye::Left => &self.left,
        }
    }
}

/// The eye stage: the iris network and its input buffer, allocation-free per call except the
/// output.
#[derive(Clone, Debug)]
pub struct IrisLandmarker {
    net: IrisNetwork,
}

impl IrisLandmarker {
    /// Loads and verifies `iris_landmark.tflite` from the model directory.
    pub fn load(models: &Path) -> Result<Self, FaceError> {
        Ok(IrisLandmarker {
            net: IrisNetwork::load(models)?,
        })
    }

    /// Like [`IrisLandmarker::load`], but `None` when the file is absent (the eyes are
    /// optional); a corrupt file is still an error.
    pub fn load_if_present(models: &Path) -> Result<Option<Self>, FaceError> {
        match Self::load(models) {
            Ok(l) => Ok(Some(l)),
            Err(FaceError::ModelMissing { .. }) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// Wraps an already compiled network.
    pub fn new(net: IrisNetwork) -> Self {
        IrisLandmarker { net }
    }

    /// The landmarks of `eye` from the face's FaceMesh landmarks `points` (frame pixels, visage
    /// convention, at least 468).
    pub fn eye(
        &mut self,
        image: &RgbImage,
        points: &[[f32; 3]],
        eye: Eye,
    ) -> Result<EyeLandmarks, FaceError> {
        if image.width() == 0 || image.height() == 0 {
            return Err(FaceError::Image {
                reason: format!("empty image {}×{}", image.width(), image.height()),
            });
        }
        let crop = EyeCrop::from_landmarks(points, eye).ok_or_else(|| FaceError::Image {
            reason: format!(
                "no {eye:?} eye crop from {} landmarks: corners {:?} missing, coincident or \
                 not finite",
                points.len(),
                eye.corners()
            ),
        })?;
        crop.sample(image, self.net.input_mut());
        Ok(EyeLandmarks::from_crop(&self.net.run(), crop))
    }

    /// Both eyes from the face's FaceMesh landmarks (two network runs).
    pub fn eyes(&mut self, image: &RgbImage, points: &[[f32; 3]]) -> Result<Eyes, FaceError> {
        Ok(Eyes {
            right: self.eye(image, points, Eye::Right)?,
            left: self.eye(image, points, Eye::Left)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_iris_file_is_optional_but_a_corrupt_one_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        assert!(IrisLandmarker::load_if_present(dir.path())
            .unwrap()
            .is_none());
        std::fs::write(dir.path().join("iris_landmark.tflite"), b"truncated").unwrap();
        let err = IrisLandmarker::load_if_present(dir.path()).unwrap_err();
        assert!(matches!(err, FaceError::ModelChecksum { .. }), "{err}");
    }

    #[test]
    fn radius_is_half_the_mean_rim_to_rim_distance() {
        let eye = EyeLandmarks {
            iris: [
                [10.0, 10.0, 0.0],
                [13.0, 10.0, 0.0],
                [10.0, 6.0, 0.0],
                [7.0, 10.0, 0.0],
                [10.0, 14.0, 0.0],
            ],
            contour: Vec::new(),
            crop: None,
        };
        assert_eq!(eye.iris_center(), [10.0, 10.0, 0.0]);
        assert!((eye.iris_radius() - 3.5).abs() < 1e-6);
    }
}
