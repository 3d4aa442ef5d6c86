//! Small fixed-size linear algebra for the transform chain: 4×4 homogeneous matrices and 3×3
//! linear parts, row-major, `f64`.

use visage_camera::vec3::normalize;
use visage_camera::RigidTransform;

/// A 4×4 homogeneous matrix, row-major (`m[row][col]`), acting on column vectors `x' = M·x`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mat4(pub [[f64; 4]; 4]);

/// A 3×3 matrix, row-major, acting on column vectors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mat3(pub [[f64; 3]; 3]);

impl Mat4 {
    /// The identity.
    pub const IDENTITY: Mat4 = Mat4([
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]);

    /// The affine map `x ↦ A·x + t`.
    pub fn from_linear_translation(a: Mat3, t: [f64; 3]) -> Mat4 {
        let a = a.0;
        Mat4([
            [a[0][0], a[0][1], a[0][2], t[0]],
            [a[1][0], a[1][1], a[1][2], t[1]],
            [a[2][0], a[2][1], a[2][2], t[2]],
            [0.0, 0.0, 0.0, 1.0],
        ])
    }

    /// The rigid motion `t` as the 4×4 matrix `[R t; 0 1]` (e.g. a camera pose, the `[R t]` of
    /// Eq. (6.1)).
    pub fn from_rigid(t: &RigidTransform) -> Mat4 {
        Mat4::from_linear_translation(Mat3(t.rotation), t.translation)
    }

    /// A translation by `t`.
    pub fn translation(t: [f64; 3]) -> Mat4 {
        Mat4::from_linear_translation(Mat3::IDENTITY, t)
    }

    /// A scaling by `s` along the axes.
    pub fn scaling(s: [f64; 3]) -> Mat4 {
        Mat4::from_linear_translation(Mat3::diagonal(s), [0.0; 3])
    }

    /// The matrix product `self · rhs` (apply `rhs` first).
    pub fn mul(&self, rhs: &Mat4) -> Mat4 {
        let (a, b) = (&self.0, &rhs.0);
        let mut m = [[0.0; 4]; 4];
        for (i, row) in m.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = (0..4).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        Mat4(m)
    }

    /// `M · (p, 1)ᵀ`, the homogeneous image of point `p`.
    #[inline]
    pub fn transform_point4(&self, p: [f64; 3]) -> [f64; 4] {
        let m = &self.0;
        let mut r = [0.0; 4];
        for (i, x) in r.iter_mut().enumerate() {
            *x = m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3];
        }
        r
    }

    /// The affine image of point `p` (the last row is assumed to be `(0, 0, 0, 1)`).
    #[inline]
    pub fn transform_point(&self, p: [f64; 3]) -> [f64; 3] {
        let r = self.transform_point4(p);
        [r[0], r[1], r[2]]
    }

    /// The upper-left 3×3 block (the linear part of an affine map).
    pub fn linear(&self) -> Mat3 {
        let m = &self.0;
        Mat3([
            [m[0][0], m[0][1], m[0][2]],
            [m[1][0], m[1][1], m[1][2]],
            [m[2][0], m[2][1], m[2][2]],
        ])
    }

    /// Whether the last row is `(0, 0, 0, 1)` and every entry is finite.
    pub fn is_finite_affine(&self) -> bool {
        self.0.iter().flatten().all(|x| x.is_finite()) && self.0[3] == [0.0, 0.0, 0.0, 1.0]
    }
}

impl Mat3 {
    /// The identity.
    pub const IDENTITY: Mat3 = Mat3([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);

    /// `diag(d)`.
    pub fn diagonal(d: [f64; 3]) -> Mat3 {
        Mat3([[d[0], 0.0, 0.0], [0.0, d[1], 0.0], [0.0, 0.0, d[2]]])
    }

    /// The rotation by `angle` radians about the unit axis `axis` (Rodrigues' formula).
    pub fn rotation(axis: [f64; 3], angle: f64) -> Mat3 {
        let [x, y, z] = normalize(axis);
        let (s, c) = angle.sin_cos();
        let t = 1.0 - c;
        Mat3([
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ])
    }

    /// `A · x`.
    #[inline]
    pub fn mul_vec(&self, x: [f64; 3]) -> [f64; 3] {
        let m = &self.0;
        [
            m[0][0] * x[0] + m[0][1] * x[1] + m[0][2] * x[2],
            m[1][0] * x[0] + m[1][1] * x[1] + m[1][2] * x[2],
            m[2][0] * x[0] + m[2][1] * x[1] + m[2][2] * x[2],
        ]
    }

    /// The matrix product `self · rhs`.
    pub fn mul(&self, rhs: &Mat3) -> Mat3 {
        let (a, b) = (&self.0, &rhs.0);
        let mut m = [[0.0; 3]; 3];
        for (i, row) in m.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = (0..3).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        Mat3(m)
    }

    /// The transpose.
    pub fn transpose(&self) -> Mat3 {
        let m = &self.0;
        Mat3([
            [m[0][0], m[1][0], m[2][0]],
            [m[0][1], m[1][1], m[2][1]],
            [m[0][2], m[1][2], m[2][2]],
        ])
    }

    /// The determinant.
    pub fn determinant(&self) -> f64 {
        let m = &self.0;
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }

    /// The inverse transpose `(A⁻¹)ᵀ = cof(A) / det(A)`, or `None` when `A` is singular
    /// (|det| below `1e-300` or not finite).
    pub fn inverse_transpose(&self) -> Option<Mat3> {
        let m = &self.0;
        let det = self.determinant();
        if !(det.is_finite() && det.abs() > 1e-300) {
            return None;
        }
        let cof = [
            [
                m[1][1] * m[2][2] - m[1][2] * m[2][1],
                m[1][2] * m[2][0] - m[1][0] * m[2][2],
                m[1][0] * m[2][1] - m[1][1] * m[2][0],
            ],
            [
                m[0][2] * m[2][1] - m[0][1] * m[2][2],
                m[0][0] * m[2][2] - m[0][2] * m[2][0],
                m[0][1] * m[2][0] - m[0][0] * m[2][1],
            ],
            [
                m[0][1] * m[1][2] - m[0][2] * m[1][1],
                m[0][2] * m[1][0] - m[0][0] * m[1][2],
                m[0][0] * m[1][1] - m[0][1] * m[1][0],
            ],
        ];
        let inv = 1.0 / det;
        Some(Mat3(cof.map(|row| row.map(|c| c * inv))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_transpose_times_transpose_is_identity() {
        let a = Mat3([[2.0, 0.5, -1.0], [0.1, 3.0, 0.2], [0.0, -0.7, 0.5]]);
        let it = a.inverse_transpose().unwrap();
        let p = it.transpose().mul(&a);
        for i in 0..3 {
            for j in 0..3 {
                let expected = if i == j { 1.0 } else { 0.0 };
                assert!((p.0[i][j] - expected).abs() < 1e-14, "{p:?}");
            }
        }
        assert!(Mat3::diagonal([1.0, 0.0, 1.0])
            .inverse_transpose()
            .is_none());
    }

    #[test]
    fn rotation_is_orthonormal_and_turns_the_right_way() {
        let r = Mat3::rotation([0.0, 0.0, 2.0], std::f64::consts::FRAC_PI_2);
        let x = r.mul_vec([1.0, 0.0, 0.0]);
        assert!((x[0]).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15);
        assert!((r.determinant() - 1.0).abs() < 1e-14);
    }
}
