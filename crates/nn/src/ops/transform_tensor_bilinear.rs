/// MediaPipe's custom operator `TransformTensorBilinear` (version 2; MediaPipe's
/// `transform_tensor_bilinear.cc`), batch 1: samples `x` (`[H, W, C]`, `in_hw = [H, W]`)
/// bilinearly over an `out_h × out_w` grid mapped into it by the affine part of `matrix`
/// (4×4 row-major, as [`super::landmarks_to_transform_matrix`] writes it), into `y`
/// (`[out_h, out_w, C]`).
///
/// Version 2 maps pixel centres: output pixel `(u, v)` reads the input at
/// `A·(u + ½, v + ½) + t − ½` (`A`, `t` the matrix's first two rows), folded into `t` once as
/// MediaPipe does. A point outside `[0, W − 1] × [0, H − 1]` (or not finite) gives zeros in
/// every channel; inside, the four neighbours are weighted as
/// `f_y·((1 − f_x)·q₁₂ + f_x·q₂₂) + (1 − f_y)·((1 − f_x)·q₁₁ + f_x·q₂₁)`, a neighbour past
/// the last row or column (weight 0 on the edge) reading 0. Allocation-free.
///
/// # Panics
/// If `x` or `y` does not have the implied size, or `matrix` holds fewer than 8 values.
#[track_caller]
pub fn transform_tensor_bilinear(
    x: &[f32],
    in_hw: [usize; 2],
    c: usize,
    matrix: &[f32],
    out_hw: [usize; 2],
    y: &mut [f32],
) {
    let ([h, w], [out_h, out_w]) = (in_hw, out_hw);
    assert_eq!(x.len(), h * w * c, "transform_tensor_bilinear input size");
    assert_eq!(
        y.len(),
        out_h * out_w * c,
        "transform_tensor_bilinear output size"
    );
    let (mut rx, mut ry) = ([0.0f32; 4], [0.0f32; 4]);
    rx.copy_from_slice(&matrix[0..4]);
    ry.copy_from_slice(&matrix[4..8]);
    // Pixel centres: T → S·T·A with A = shift by +½, S = shift by −½.
    rx[3] += rx[0] * 0.5 + rx[1] * 0.5 - 0.5;
    ry[3] += ry[0] * 0.5 + ry[1] * 0.5 - 0.5;
    let (last_x, last_y) = (w as f32 - 1.0, h as f32 - 1.0);
    let read = |row: isize, col: isize| -> Option<&[f32]> {
        let (row, col) = (usize::try_from(row).ok()?, usize::try_from(col).ok()?);
        (row < h && col < w).then(|| &x[(row * w + col) * c..(row * w + col + 1) * c])
    };
    for (p, out) in y.chunks_exact_mut(c.max(1)).enumerate().take(out_h * out_w) {
        let (u, v) = ((p % out_w) as f32, (p / out_w) as f32);
        let tx = rx[0] * u + rx[1] * v + rx[2] * 0.0 + rx[3];
        let ty = ry[0] * u + ry[1] * v + ry[2] * 0.0 + ry[3];
        // `!(inside)` also sends NaN to the zeros.
        if !(tx >= 0.0 && tx <= last_x && ty >= 0.0 && ty <= last_y) {
            out.fill(0.0);
            continue;
        }
        let (fx, fy) = (tx.floor(), ty.floor());
        let (right, lower) = (tx - fx, ty - fy);
        let (col, row) = (fx as isize, fy as isize);
        let (q11, q21) = (read(row, col), read(row, col + 1));
        let (q12, q22) = (read(row + 1, col), read(row + 1, col + 1));
        let mix = |q11: f32, q21: f32, q12: f32, q22: f32| {
            let upper = (1.0 - right) * q11 + right * q21;
            let below = (1.0 - right) * q12 + right * q22;
            lower * below + (1.0 - lower) * upper
        };
        if let (Some(q11), Some(q21), Some(q12), Some(q22)) = (q11, q21, q12, q22) {
            // Inside: four whole channel rows, a loop the compiler vectorises.
            for ((((o, &a), &b), &c), &d) in out.iter_mut().zip(q11).zip(q21).zip(q12).zip(q22) {
                *o = mix(a, b, c, d);
            }
        } else {
            // On the last row or column: the neighbours past it read 0 (with weight 0).
            let at = |q: Option<&[f32]>, k: usize| q.map_or(0.0, |q| q[k]);
            for (k, o) in out.iter_mut().enumerate() {
                *o = mix(at(q11, k), at(q21, k), at(q12, k), at(q22, k));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const IDENTITY: [f32; 16] = [
        1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    ];

    /// A 3×4 image with two channels: `(10·row + col, −(10·row + col))`.
    fn image() -> Vec<f32> {
        (0..3)
            .flat_map(|r| (0..4).flat_map(move |c| [(10 * r + c) as f32, -((10 * r + c) as f32)]))
            .collect()
    }

    #[test]
    fn the_identity_gives_the_input_back() {
        let x = image();
        let mut y = vec![9.0; x.len()];
        transform_tensor_bilinear(&x, [3, 4], 2, &IDENTITY, [3, 4], &mut y);
        assert_eq!(y, x);
    }

    #[test]
    fn half_a_pixel_interpolates_and_outside_is_zero() {
        // (u, v) → (u + ½, v − 1): row −1 is outside, the others average two columns; the last
        // column's neighbour lies past the edge.
        let mut m = IDENTITY;
        m[3] = 0.5;
        m[7] = -1.0;
        let x = image();
        let mut y = vec![9.0; 3 * 4 * 2];
        transform_tensor_bilinear(&x, [3, 4], 2, &m, [3, 4], &mut y);
        let expected: Vec<f32> = (0..3)
            .flat_map(|v| {
                (0..4).flat_map(move |u| {
                    let v = 10.0 * (v as f32 - 1.0) + u as f32 + 0.5;
                    if v < 0.0 || u == 3 {
                        [0.0, 0.0]
                    } else {
                        [v, -v]
                    }
                })
            })
            .collect();
        assert_eq!(y, expected);
    }

    #[test]
    fn a_quarter_turn_transposes() {
        // (u, v) → (v, u) about pixel centres: A = [[0, 1], [1, 0]], t chosen so that the
        // half-pixel shifts cancel. A 4×3 output of the 3×4 image is its transpose.
        let mut m = IDENTITY;
        m[..4].copy_from_slice(&[0.0, 1.0, 0.0, 0.0]);
        m[4..8].copy_from_slice(&[1.0, 0.0, 0.0, 0.0]);
        let x = image();
        let mut y = vec![9.0; 4 * 3 * 2];
        transform_tensor_bilinear(&x, [3, 4], 2, &m, [4, 3], &mut y);
        for v in 0..4 {
            for u in 0..3 {
                let at = (v * 3 + u) * 2;
                assert_eq!(y[at], (10 * u + v) as f32, "({u}, {v})");
            }
        }
        // A matrix of NaN reads nothing.
        transform_tensor_bilinear(&x, [3, 4], 2, &[f32::NAN; 16], [4, 3], &mut y);
        assert!(y.iter().all(|&v| v == 0.0));
    }
}
