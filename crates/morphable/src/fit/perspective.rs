//! The pinhole projection of a camera-space point and its Jacobian, for the fit's linearised
//! steps (visage's camera: x right, y down, z forward; pixel centres at integers).

use visage_camera::Intrinsics;

/// `π(Y) = (f_x Y_x / Y_z + c_x, f_y Y_y / Y_z + c_y)` and `∂π/∂Y` (2 × 3, rows u and v).
pub fn project_with_jacobian(k: &Intrinsics, y: [f64; 3]) -> ([f64; 2], [[f64; 3]; 2]) {
    let iz = 1.0 / y[2];
    let (x, v) = (y[0] * iz, y[1] * iz);
    (
        [k.fx * x + k.cx, k.fy * v + k.cy],
        [
            [k.fx * iz, 0.0, -k.fx * x * iz],
            [0.0, k.fy * iz, -k.fy * v * iz],
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobian_matches_finite_differences() {
        let k = Intrinsics::new(640, 480, 500.0, 520.0, 319.5, 239.5).unwrap();
        let y = [0.03, -0.02, 0.55];
        let (p, j) = project_with_jacobian(&k, y);
        let q = k.project(y);
        assert!((p[0] - q[0]).abs() < 1e-9 && (p[1] - q[1]).abs() < 1e-9);
        for c in 0..3 {
            let mut z = y;
            z[c] += 1e-7;
            let q = k.project(z);
            for r in 0..2 {
                assert!(((q[r] - p[r]) / 1e-7 - j[r][c]).abs() < 1e-3 * j[r][c].abs().max(1.0));
            }
        }
    }
}
