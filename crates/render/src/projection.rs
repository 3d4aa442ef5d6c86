use visage_camera::Intrinsics;

use crate::mat4::Mat4;

/// The OpenGL projection matrix `P` of Eq. (6.1) built from the intrinsics `K` (ERRATA 12), for
/// OpenGL eye space (x right, y up, looking down −z) and clipping planes `near < far` (metres).
///
/// ```text
///     ⎡ 2fx/W    0       1 − (2cx+1)/W     0          ⎤
/// P = ⎢ 0        2fy/H   (2cy+1)/H − 1     0          ⎥
///     ⎢ 0        0       −(f+n)/(f−n)      −2fn/(f−n) ⎥
///     ⎣ 0        0       −1                0          ⎦
/// ```
///
/// The `+1` in `2cx + 1` (ERRATA 12 prints `2cx/W − 1`) comes from the crate's pixel convention:
/// the centre of pixel `(i, j)` is at `(i, j)`, so the image spans `[−½, W − ½] × [−½, H − ½]`
/// and NDC `x = −1` is the left edge of pixel 0. With this `P` and [`viewport`], a point at depth
/// `z` lands exactly on `Intrinsics::project`; `z = near` maps to NDC depth −1, `z = far` to +1.
pub fn projection_matrix(k: &Intrinsics, near: f64, far: f64) -> Mat4 {
    let (w, h) = (k.width as f64, k.height as f64);
    let (n, f) = (near, far);
    Mat4([
        [2.0 * k.fx / w, 0.0, 1.0 - (2.0 * k.cx + 1.0) / w, 0.0],
        [0.0, 2.0 * k.fy / h, (2.0 * k.cy + 1.0) / h - 1.0, 0.0],
        [0.0, 0.0, -(f + n) / (f - n), -2.0 * f * n / (f - n)],
        [0.0, 0.0, -1.0, 0.0],
    ])
}

/// The change of axes from the crate's camera coordinates (x right, y down, z forward) to OpenGL
/// eye coordinates (x right, y up, z backward): `diag(1, −1, −1, 1)`.
pub const CAMERA_TO_EYE: Mat4 = Mat4([
    [1.0, 0.0, 0.0, 0.0],
    [0.0, -1.0, 0.0, 0.0],
    [0.0, 0.0, -1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
]);

/// The viewport transform: NDC `(x, y)` ∈ [−1, 1]² (y up) → pixel position `(u, v)` (v down,
/// pixel centres at integers): `u = ((x + 1)·W − 1)/2`, `v = ((1 − y)·H − 1)/2`.
#[inline]
pub fn viewport(width: u32, height: u32, ndc: [f64; 2]) -> [f64; 2] {
    [
        0.5 * ((ndc[0] + 1.0) * width as f64 - 1.0),
        0.5 * ((1.0 - ndc[1]) * height as f64 - 1.0),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_then_viewport_equals_the_pinhole_projection() {
        let k = Intrinsics::new(640, 480, 525.0, 530.0, 310.25, 245.5).unwrap();
        let (near, far) = (0.05, 20.0);
        let p = projection_matrix(&k, near, far).mul(&CAMERA_TO_EYE);
        for cam in [
            [0.1, -0.2, 0.7],
            [-1.0, 0.5, 3.0],
            [0.0, 0.0, near],
            [0.3, 0.1, far],
        ] {
            let clip = p.transform_point4(cam);
            assert!((clip[3] - cam[2]).abs() < 1e-15, "w = z");
            let ndc = [clip[0] / clip[3], clip[1] / clip[3], clip[2] / clip[3]];
            let px = viewport(k.width, k.height, [ndc[0], ndc[1]]);
            let expected = k.project(cam);
            assert!((px[0] - expected[0]).abs() < 1e-9 && (px[1] - expected[1]).abs() < 1e-9);
            if cam[2] == near {
                assert!((ndc[2] + 1.0).abs() < 1e-12);
            }
            if cam[2] == far {
                assert!((ndc[2] - 1.0).abs() < 1e-12);
            }
        }
    }
}
