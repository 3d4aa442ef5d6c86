use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::mat4::{Mat3, Mat4};
use crate::RenderError;

/// Largest deviation of `RᵀR` from the identity accepted for a rotation.
pub const ROTATION_TOLERANCE: f64 = 1e-6;

/// A rigid world → camera transform `x_cam = R · x_world + t` (the matrix `V` of Eq. (6.1), in the
/// camera convention of the crate: x right, y down, z forward, metres).
///
/// The JSON form (`--pose pose.json`) is
/// `{"rotation": [[r00, r01, r02], [r10, r11, r12], [r20, r21, r22]], "translation": [tx, ty, tz]}`,
/// rows of `R`, `t` in metres — the OpenCV extrinsics `[R | t]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// `R`, row-major, a proper rotation (`RᵀR = I`, `det R = +1`).
    pub rotation: [[f64; 3]; 3],
    /// `t` in metres.
    pub translation: [f64; 3],
}

impl Default for Pose {
    fn default() -> Self {
        Pose::IDENTITY
    }
}

impl Pose {
    /// World coordinates = camera coordinates.
    pub const IDENTITY: Pose = Pose {
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.0; 3],
    };

    /// A validated pose: `R` a rotation within [`ROTATION_TOLERANCE`], everything finite.
    pub fn new(rotation: [[f64; 3]; 3], translation: [f64; 3]) -> Result<Pose, RenderError> {
        let pose = Pose {
            rotation,
            translation,
        };
        pose.validate()?;
        Ok(pose)
    }

    /// Checks that `R` is a proper rotation and `t` is finite.
    pub fn validate(&self) -> Result<(), RenderError> {
        let bad = |reason: String| RenderError::Transform {
            what: "pose",
            reason,
        };
        if !self
            .rotation
            .iter()
            .flatten()
            .chain(&self.translation)
            .all(|x| x.is_finite())
        {
            return Err(bad(format!("non-finite entry in {self:?}")));
        }
        let r = Mat3(self.rotation);
        let rtr = r.transpose().mul(&r);
        for i in 0..3 {
            for j in 0..3 {
                let expected = if i == j { 1.0 } else { 0.0 };
                let dev = (rtr.0[i][j] - expected).abs();
                if dev > ROTATION_TOLERANCE {
                    return Err(bad(format!(
                        "rotation is not orthonormal: (RᵀR)[{i}][{j}] deviates by {dev:e}"
                    )));
                }
            }
        }
        let det = r.determinant();
        if det < 0.0 {
            return Err(bad(format!("rotation is a reflection (det = {det})")));
        }
        Ok(())
    }

    /// The 4×4 matrix `[R t; 0 1]`.
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_linear_translation(Mat3(self.rotation), self.translation)
    }

    /// Reads and validates a pose JSON file; errors name the file.
    pub fn load_json(path: &Path) -> Result<Pose, RenderError> {
        let file_err = |reason: String| RenderError::File {
            path: path.to_owned(),
            reason,
        };
        let text = std::fs::read_to_string(path).map_err(|e| file_err(e.to_string()))?;
        let pose: Pose = serde_json::from_str(&text)
            .map_err(|e| file_err(format!("not a valid pose file: {e}")))?;
        pose.validate().map_err(|e| file_err(e.to_string()))?;
        Ok(pose)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_non_rotations_and_names_the_file() {
        assert!(Pose::new(
            [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            [0.0; 3]
        )
        .is_err());
        assert!(Pose::new(
            [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            [0.0; 3]
        )
        .is_err());
        assert!(Pose::new(Pose::IDENTITY.rotation, [f64::NAN, 0.0, 0.0]).is_err());
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("pose.json");
        std::fs::write(
            &path,
            r#"{"rotation": [[1,0,0],[0,1,0],[0,0,1]], "translation": [0, 0, 0.5]}"#,
        )
        .unwrap();
        assert_eq!(Pose::load_json(&path).unwrap().translation, [0.0, 0.0, 0.5]);
        std::fs::write(
            &path,
            r#"{"rotation": [[1,0,0],[0,1,0]], "translation": [0, 0, 0.5]}"#,
        )
        .unwrap();
        let err = Pose::load_json(&path).unwrap_err().to_string();
        assert!(err.contains("pose.json"), "{err}");
    }
}
