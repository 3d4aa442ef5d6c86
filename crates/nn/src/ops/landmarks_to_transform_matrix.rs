/// MediaPipe's custom operator `Landmarks2TransformMatrix` (version 2; MediaPipe's
/// `landmarks_to_transform_matrix.cc`): the affine map from an `out_h × out_w` crop to the
/// input's pixels of a rotated box around some landmarks — the region the attention face
/// mesh looks at again for the lips and each eye.
///
/// With `θ = target_rotation − atan2(y_r − y_l, x_r − x_l)` (`l`, `r` the landmarks at
/// `left`, `right`): the `subset` landmarks turned by `θ` have a bounding box of size
/// `w × h` whose centre, turned back by `−θ`, is `c`. Crop pixel `(u, v)` maps to
/// `c + R(−θ) · diag(scale_x·w/out_w, scale_y·h/out_h) · (u − out_w/2, v − out_h/2)`, where
/// `R(φ)` turns by `φ` (counter-clockwise in a y-up frame).
#[derive(Clone, Debug, PartialEq)]
pub struct LandmarksToTransformMatrix {
    /// Landmark that sets the rotation's origin (`left_rotation_idx`).
    pub left: usize,
    /// Landmark that sets the rotation's direction (`right_rotation_idx`).
    pub right: usize,
    /// The angle the `left → right` direction is turned to, radians
    /// (`target_rotation_radians`).
    pub target_rotation: f32,
    /// `[out_h, out_w]`, the crop's size in pixels (`output_height`, `output_width`).
    pub output_size: [usize; 2],
    /// `[scale_x, scale_y]`: the crop's size over the landmarks' box (`scale_x`, `scale_y`).
    pub scale: [f32; 2],
    /// The landmarks whose box the crop covers (`subset_idxs`).
    pub subset: Vec<usize>,
}

/// Writes the 4×4 row-major matrix of [`LandmarksToTransformMatrix`] for `landmarks`
/// (`[N, 3]`: x, y, z per landmark, z unused) into `matrix`: rows
/// `[a₀₀, a₀₁, 0, t_x]`, `[a₁₀, a₁₁, 0, t_y]`, `[0, 0, 1, 0]`, `[0, 0, 0, 1]`, so that input
/// `(x, y) = A·(u, v) + t` for crop pixel `(u, v)`. In f32, in the order of MediaPipe's
/// kernel; allocation-free.
///
/// # Panics
/// If an index is outside `landmarks` or `matrix` does not hold 16 values.
#[track_caller]
pub fn landmarks_to_transform_matrix(
    landmarks: &[f32],
    op: &LandmarksToTransformMatrix,
    matrix: &mut [f32],
) {
    assert_eq!(matrix.len(), 16, "transform matrix size");
    let xy = |i: usize| [landmarks[3 * i], landmarks[3 * i + 1]];
    let (l, r) = (xy(op.left), xy(op.right));
    let theta = op.target_rotation - (r[1] - l[1]).atan2(r[0] - l[0]);
    let (sin, cos) = theta.sin_cos();
    let turned = |p: [f32; 2]| [p[0] * cos - p[1] * sin, p[0] * sin + p[1] * cos];
    let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    for &i in &op.subset {
        let p = turned(xy(i));
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
    // The box's centre, turned back by −θ.
    let mid = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let c = [mid[0] * cos + mid[1] * sin, -mid[0] * sin + mid[1] * cos];
    let [out_h, out_w] = op.output_size.map(|s| s as f32);
    let (sx, sy) = (op.scale[0] * w / out_w, op.scale[1] * h / out_h);
    // R(−θ) · diag(sx, sy), then the shift by −(out_w/2, out_h/2) folded into t.
    let a = [[cos * sx, sin * sy], [-sin * sx, cos * sy]];
    let (du, dv) = (-(out_w / 2.0), -(out_h / 2.0));
    let t = [
        a[0][0] * du + a[0][1] * dv + c[0],
        a[1][0] * du + a[1][1] * dv + c[1],
    ];
    matrix.copy_from_slice(&[
        a[0][0], a[0][1], 0.0, t[0], //
        a[1][0], a[1][1], 0.0, t[1], //
        0.0, 0.0, 1.0, 0.0, //
        0.0, 0.0, 0.0, 1.0,
    ]);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn op(
        subset: Vec<usize>,
        output_size: [usize; 2],
        scale: [f32; 2],
    ) -> LandmarksToTransformMatrix {
        LandmarksToTransformMatrix {
            left: 0,
            right: 1,
            target_rotation: 0.0,
            output_size,
            scale,
            subset,
        }
    }

    /// `(x, y)` of crop pixel `(u, v)` under `m`.
    fn apply(m: &[f32], u: f32, v: f32) -> [f32; 2] {
        [m[0] * u + m[1] * v + m[3], m[4] * u + m[5] * v + m[7]]
    }

    #[test]
    fn level_landmarks_give_a_scaled_shift() {
        // Corners of the box [1, 3] × [1, 5]; left → right is level, so θ = 0.
        let landmarks = [1.0, 1.0, 0.0, 3.0, 1.0, 0.0, 1.0, 5.0, 0.0, 3.0, 5.0, 9.0];
        let mut m = [0.0; 16];
        landmarks_to_transform_matrix(
            &landmarks,
            &op(vec![0, 1, 2, 3], [4, 2], [1.0, 1.0]),
            &mut m,
        );
        // Crop 2 wide × 4 high over a 2 × 4 box: unit scale, (u, v) → (u + 1, v + 1).
        let expected = [
            1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        assert_eq!(m, expected);
        // Scale 1.5 around the centre (2, 3): the crop's centre still maps there.
        landmarks_to_transform_matrix(
            &landmarks,
            &op(vec![0, 1, 2, 3], [4, 2], [1.5, 1.5]),
            &mut m,
        );
        assert_eq!([m[0], m[5]], [1.5, 1.5]);
        assert_eq!(apply(&m, 1.0, 2.0), [2.0, 3.0]);
    }

    #[test]
    fn a_turned_box_gives_its_rotation() {
        // A 4 × 2 box (long side from the left to the right landmark) turned by 30° about
        // (10, 20): left corner (10, 20), right corner along 30°, the other two across.
        let (s, c) = 30f32.to_radians().sin_cos();
        let (ex, ey) = ([c, s], [-s, c]);
        let corner = |a: f32, b: f32| [10.0 + a * ex[0] + b * ey[0], 20.0 + a * ex[1] + b * ey[1]];
        let pts = [
            corner(0.0, 0.0),
            corner(4.0, 0.0),
            corner(0.0, 2.0),
            corner(4.0, 2.0),
        ];
        let landmarks: Vec<f32> = pts.iter().flat_map(|p| [p[0], p[1], 0.0]).collect();
        let mut m = [0.0; 16];
        landmarks_to_transform_matrix(
            &landmarks,
            &op(vec![0, 1, 2, 3], [2, 4], [1.0, 1.0]),
            &mut m,
        );
        // The crop's axes are the box's: u along ex, v along ey, one pixel a unit.
        for (got, want) in [m[0], m[4], m[1], m[5]]
            .iter()
            .zip([ex[0], ex[1], ey[0], ey[1]])
        {
            assert!((got - want).abs() < 1e-6, "{m:?}");
        }
        // Its corners map to the box's corners.
        for (uv, p) in [[0.0, 0.0], [4.0, 0.0], [0.0, 2.0], [4.0, 2.0]]
            .iter()
            .zip(pts)
        {
            let q = apply(&m, uv[0], uv[1]);
            assert!(
                (q[0] - p[0]).abs() < 1e-5 && (q[1] - p[1]).abs() < 1e-5,
                "{q:?} {p:?}"
            );
        }
        assert_eq!(m[8..], [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    }
}
