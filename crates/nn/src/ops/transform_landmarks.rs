/// MediaPipe's custom operator `TransformLandmarks` (version 2; MediaPipe's
/// `transform_landmarks.cc`): maps points (`[N, D]`, `D` = 2 or 3 values each) by the affine
/// part of `matrix` (4×4 row-major): `(x, y) → A·(x, y) + t` from its first two rows, `z`
/// (when `D` = 3) copied. Allocation-free.
///
/// # Panics
/// If `points` and `y` differ in size, their size is not a multiple of `dims`, `dims` is not 2
/// or 3, or `matrix` holds fewer than 8 values.
#[track_caller]
pub fn transform_landmarks(points: &[f32], dims: usize, matrix: &[f32], y: &mut [f32]) {
    assert!(
        dims == 2 || dims == 3,
        "transform_landmarks: {dims} values a point"
    );
    assert_eq!(points.len(), y.len(), "transform_landmarks sizes");
    assert_eq!(points.len() % dims, 0, "transform_landmarks: whole points");
    let (rx, ry) = (&matrix[0..4], &matrix[4..8]);
    for (p, q) in points.chunks_exact(dims).zip(y.chunks_exact_mut(dims)) {
        // MediaPipe's dot product with (x, y, 0, 1), in its order.
        q[0] = rx[0] * p[0] + rx[1] * p[1] + rx[2] * 0.0 + rx[3];
        q[1] = ry[0] * p[0] + ry[1] * p[1] + ry[2] * 0.0 + ry[3];
        if dims == 3 {
            q[2] = p[2];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_xy_and_keeps_z() {
        // x' = 2x − y + 1, y' = x + 3y − 2.
        let m = [
            2.0, -1.0, 7.0, 1.0, 1.0, 3.0, 7.0, -2.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        let mut y = [0.0; 6];
        transform_landmarks(&[1.0, 2.0, 5.0, -1.0, 0.0, 6.0], 3, &m, &mut y);
        assert_eq!(y, [1.0, 5.0, 5.0, -1.0, -3.0, 6.0]);
        let mut y = [0.0; 4];
        transform_landmarks(&[1.0, 2.0, 0.5, 0.5], 2, &m, &mut y);
        assert_eq!(y, [1.0, 5.0, 1.5, 0.0]);
    }
}
