//! Turntable views: the model spun about a vertical axis through its centre.

use crate::mat4::{Mat3, Mat4};

/// `n` model matrices `M_k = T(c) · R_y(2πk/n) · T(−c)`, `k = 0 … n−1`: rotations about the
/// camera's vertical (y, pointing down) axis through the centre `c` of the bounding box of
/// `vertices`. View 0 is the identity. Returns an empty list for `n = 0` or no vertices.
pub fn turntable(vertices: &[[f64; 3]], n: usize) -> Vec<Mat4> {
    if vertices.is_empty() {
        return Vec::new();
    }
    (0..n)
        .map(|k| turn_about_centre(vertices, std::f64::consts::TAU * k as f64 / n as f64))
        .collect()
}

/// `T(c) · R_y(angle) · T(−c)`: a turn by `angle` about the camera's vertical axis through the
/// centre `c` of the bounding box of `vertices` (the identity for no vertices).
pub fn turn_about_centre(vertices: &[[f64; 3]], angle: f64) -> Mat4 {
    if vertices.is_empty() {
        return Mat4::IDENTITY;
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in vertices {
        for k in 0..3 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    let c: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let r = Mat4::from_linear_translation(Mat3::rotation([0.0, 1.0, 0.0], angle), [0.0; 3]);
    Mat4::translation(c)
        .mul(&r)
        .mul(&Mat4::translation([-c[0], -c[1], -c[2]]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_keep_the_centre_and_half_turn_mirrors_x_and_z() {
        let v = [[0.0, 0.0, 1.0], [0.2, 0.1, 1.4]];
        let m = turntable(&v, 4);
        assert_eq!(m.len(), 4);
        assert_eq!(m[0], Mat4::IDENTITY);
        let c = [0.1, 0.05, 1.2];
        let half = m[2].transform_point(v[1]);
        for k in 0..3 {
            assert!((m[1].transform_point(c)[k] - c[k]).abs() < 1e-12);
        }
        assert!(
            (half[0] - 0.0).abs() < 1e-12
                && (half[1] - 0.1).abs() < 1e-12
                && (half[2] - 1.0).abs() < 1e-12
        );
        assert!(turntable(&[], 3).is_empty());
    }
}
