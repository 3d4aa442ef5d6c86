//! Rigid motions of camera space, e.g. a head pose `X_cam = R · X_head + t` or a renderer's
//! world → camera pose `x_cam = R · x_world + t`.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::CameraError;

/// Largest deviation of `RᵀR` from the identity accepted for a rotation
/// ([`RigidTransform::validate`]).
pub const ROTATION_TOLERANCE: f64 = 1e-6;

/// A rigid motion `x ↦ R · x + t` (R a rotation, row-major; t in metres).
///
/// The JSON form (serde; e.g. `visage render --pose pose.json`) is
/// `{"rotation": [[r00, r01, r02], [r10, r11, r12], [r20, r21, r22]], "translation": [tx, ty, tz]}`,
/// rows of `R`, `t` in metres — as a world → camera pose, the OpenCV extrinsics `[R | t]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RigidTransform {
    /// Rotation, row-major.
    pub rotation: [[f64; 3]; 3],
    /// Translation, metres.
    pub translation: [f64; 3],
}

impl Default for RigidTransform {
    fn default() -> Self {
        RigidTransform::IDENTITY
    }
}

impl RigidTransform {
    /// `x ↦ x`.
    pub const IDENTITY: RigidTransform = RigidTransform {
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.0; 3],
    };

    /// `R · x + t`.
    pub fn apply(&self, x: [f64; 3]) -> [f64; 3] {
        let r = &self.rotation;
        std::array::from_fn(|i| {
            r[i][0] * x[0] + r[i][1] * x[1] + r[i][2] * x[2] + self.translation[i]
        })
    }

    /// `R · x` (a direction: no translation).
    pub fn rotate(&self, x: [f64; 3]) -> [f64; 3] {
        let r = &self.rotation;
        std::array::from_fn(|i| r[i][0] * x[0] + r[i][1] * x[1] + r[i][2] * x[2])
    }

    /// `Rᵀ · (x − t)`, the inverse motion.
    pub fn apply_inverse(&self, x: [f64; 3]) -> [f64; 3] {
        let d: [f64; 3] = std::array::from_fn(|i| x[i] - self.translation[i]);
        let r = &self.rotation;
        std::array::from_fn(|i| r[0][i] * d[0] + r[1][i] * d[1] + r[2][i] * d[2])
    }

    /// Whether every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.rotation
            .iter()
            .flatten()
            .chain(&self.translation)
            .all(|v| v.is_finite())
    }

    /// A validated transform: `R` a proper rotation within [`ROTATION_TOLERANCE`], everything
    /// finite ([`RigidTransform::validate`]).
    pub fn new(
        rotation: [[f64; 3]; 3],
        translation: [f64; 3],
    ) -> Result<RigidTransform, CameraError> {
        let t = RigidTransform {
            rotation,
            translation,
        };
        t.validate()?;
        Ok(t)
    }

    /// Checks that every entry is finite and `R` is a proper rotation: each entry of `RᵀR`
    /// within [`ROTATION_TOLERANCE`] of the identity's, `det R ≥ 0`.
    ///
    /// # Errors
    /// [`CameraError::InvalidTransform`], naming the offending entry or the determinant.
    pub fn validate(&self) -> Result<(), CameraError> {
        let bad = |reason: String| CameraError::InvalidTransform { reason };
        if !self.is_finite() {
            return Err(bad(format!("non-finite entry in {self:?}")));
        }
        let r = &self.rotation;
        for i in 0..3 {
            for j in 0..3 {
                // (RᵀR)[i][j] = Σ_k R[k][i] · R[k][j].
                let rtr: f64 = (0..3).map(|k| r[k][i] * r[k][j]).sum();
                let expected = if i == j { 1.0 } else { 0.0 };
                let dev = (rtr - expected).abs();
                if dev > ROTATION_TOLERANCE {
                    return Err(bad(format!(
                        "rotation is not orthonormal: (RᵀR)[{i}][{j}] deviates by {dev:e}"
                    )));
                }
            }
        }
        let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
            - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
            + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
        if det < 0.0 {
            return Err(bad(format!("rotation is a reflection (det = {det})")));
        }
        Ok(())
    }

    /// Reads and validates the JSON form (see [`RigidTransform`]).
    ///
    /// # Errors
    /// [`CameraError::TransformFile`], naming the file and the problem: unreadable, not the
    /// expected JSON, or not a rigid motion ([`RigidTransform::validate`]).
    pub fn load_json(path: &Path) -> Result<RigidTransform, CameraError> {
        let text = std::fs::read_to_string(path).map_err(|e| CameraError::TransformFile {
            path: path.to_owned(),
            reason: e.to_string(),
        })?;
        Self::parse_json(&text, path)
    }

    /// [`RigidTransform::load_json`] of a file's text already in memory; `path` is the file it
    /// came from, named in errors.
    ///
    /// # Errors
    /// [`CameraError::TransformFile`], naming `path` and the problem: not the expected JSON, or
    /// not a rigid motion ([`RigidTransform::validate`]).
    pub fn parse_json(text: &str, path: &Path) -> Result<RigidTransform, CameraError> {
        let file_err = |reason: String| CameraError::TransformFile {
            path: path.to_owned(),
            reason,
        };
        let t: RigidTransform = serde_json::from_str(text.trim_start_matches('\u{feff}'))
            .map_err(|e| file_err(format!("not a valid pose file: {e}")))?;
        t.validate().map_err(|e| file_err(e.to_string()))?;
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> RigidTransform {
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        RigidTransform {
            rotation: [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
            translation: [0.01, -0.02, 0.5],
        }
    }

    #[test]
    fn apply_inverse_undoes_the_motion() {
        let t = sample();
        let x = [0.1, 0.2, -0.3];
        let back = t.apply_inverse(t.apply(x));
        let forth = t.apply(t.apply_inverse(x));
        for a in 0..3 {
            assert!((back[a] - x[a]).abs() < 1e-15 && (forth[a] - x[a]).abs() < 1e-15);
            // A direction turns but does not move.
            assert!((t.rotate(x)[a] + t.translation[a] - t.apply(x)[a]).abs() < 1e-15);
        }
    }

    #[test]
    fn rejects_non_rotations_and_names_the_file() {
        assert!(RigidTransform::new(sample().rotation, sample().translation).is_ok());
        assert!(RigidTransform::new(
            [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            [0.0; 3]
        )
        .is_err());
        assert!(RigidTransform::new(
            [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            [0.0; 3]
        )
        .is_err());
        assert!(
            RigidTransform::new(RigidTransform::IDENTITY.rotation, [f64::NAN, 0.0, 0.0]).is_err()
        );
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("pose.json");
        std::fs::write(
            &path,
            r#"{"rotation": [[1,0,0],[0,1,0],[0,0,1]], "translation": [0, 0, 0.5]}"#,
        )
        .unwrap();
        assert_eq!(
            RigidTransform::load_json(&path).unwrap().translation,
            [0.0, 0.0, 0.5]
        );
        std::fs::write(
            &path,
            r#"{"rotation": [[1,0,0],[0,1,0]], "translation": [0, 0, 0.5]}"#,
        )
        .unwrap();
        let err = RigidTransform::load_json(&path).unwrap_err().to_string();
        assert!(err.contains("pose.json"), "{err}");
        std::fs::write(
            &path,
            r#"{"rotation": [[1,0,0],[0,1,0],[0,0,-1]], "translation": [0, 0, 0.5]}"#,
        )
        .unwrap();
        let err = RigidTransform::load_json(&path).unwrap_err().to_string();
        assert!(
            err.contains("pose.json") && err.contains("reflection"),
            "{err}"
        );
    }
}
