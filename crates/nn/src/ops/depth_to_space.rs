/// `DEPTH_TO_SPACE` (TensorFlow's DCR order), batch 1: `x` is `[H, W, b²·C]`, `y` is
/// `[H·b, W·b, C]` with `y[yy·b + i, xx·b + j, c] = x[yy, xx, (i·b + j)·C + c]`.
///
/// Copies only; not inlined into the step loop.
///
/// # Panics
/// If `x` or `y` does not have the implied size.
#[track_caller]
#[inline(never)]
pub fn depth_to_space(x: &[f32], h: usize, w: usize, c_out: usize, block: usize, y: &mut [f32]) {
    let c_in = block * block * c_out;
    assert_eq!(x.len(), h * w * c_in, "depth_to_space input size");
    assert_eq!(y.len(), x.len(), "depth_to_space output size");
    let out_w = w * block;
    for yy in 0..h {
        for xx in 0..w {
            let src = &x[(yy * w + xx) * c_in..(yy * w + xx + 1) * c_in];
            for i in 0..block {
                for j in 0..block {
                    let dst = ((yy * block + i) * out_w + xx * block + j) * c_out;
                    let from = (i * block + j) * c_out;
                    y[dst..dst + c_out].copy_from_slice(&src[from..from + c_out]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dcr_order_by_hand() {
        // One pixel with 4 channels [a, b, c, d], block 2 → 2×2×1: [[a, b], [c, d]].
        let mut y = [0.0; 4];
        depth_to_space(&[1.0, 2.0, 3.0, 4.0], 1, 1, 1, 2, &mut y);
        assert_eq!(y, [1.0, 2.0, 3.0, 4.0]);
        // 1×2 pixels with 8 channels each, C_out = 2: pixel p, sub-position s = i·2 + j holds
        // channels (10p + 2s, 10p + 2s + 1).
        let x: Vec<f32> = (0..2)
            .flat_map(|p| (0..8).map(move |k| (10 * p + k) as f32))
            .collect();
        let mut y = [0.0; 16];
        depth_to_space(&x, 1, 2, 2, 2, &mut y);
        // Output 2×4×2, row 0: (p0,s0) (p0,s1) (p1,s0) (p1,s1); row 1: s2, s3.
        let expected = [
            0.0, 1.0, 2.0, 3.0, 10.0, 11.0, 12.0, 13.0, //
            4.0, 5.0, 6.0, 7.0, 14.0, 15.0, 16.0, 17.0,
        ];
        assert_eq!(y, expected);
    }
}
