//! Rigid motions of camera space, e.g. a head pose `X_cam = R · X_head + t`.

use serde::{Deserialize, Serialize};

/// A rigid motion `x ↦ R · x + t` (R a rotation, row-major; t in metres).
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
}
