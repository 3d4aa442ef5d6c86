use super::Window;

/// Depthwise 2-D convolution with depth multiplier 1, NHWC, as TFLite's `DEPTHWISE_CONV_2D`:
/// `y[oy, ox, c] = b[c] + Σ w[ky, kx, c] · x[oy·s + ky − pad, ox·s + kx − pad, c]` (zero outside).
///
/// `x` is `[in_h, in_w, C]`, `w` is `[k_h, k_w, C]` (TFLite's `[1, k_h, k_w, C]`), `b` is `[C]`,
/// `y` is `[out_h, out_w, C]`.
///
/// # Panics
/// If a slice length does not match the window and channel count.
#[track_caller]
pub fn depthwise_conv2d(x: &[f32], win: &Window, c: usize, w: &[f32], b: &[f32], y: &mut [f32]) {
    assert_eq!(x.len(), win.in_h * win.in_w * c, "depthwise input size");
    assert_eq!(y.len(), win.out_h * win.out_w * c, "depthwise output size");
    assert_eq!(w.len(), win.k_h * win.k_w * c, "depthwise kernel size");
    assert_eq!(b.len(), c, "depthwise bias size");
    for oy in 0..win.out_h {
        for ox in 0..win.out_w {
            let out = &mut y[(oy * win.out_w + ox) * c..][..c];
            out.copy_from_slice(b);
            for ky in 0..win.k_h {
                let Some(iy) = Window::tap(oy, win.stride_h, ky, win.pad_top, win.in_h) else {
                    continue;
                };
                for kx in 0..win.k_w {
                    let Some(ix) = Window::tap(ox, win.stride_w, kx, win.pad_left, win.in_w) else {
                        continue;
                    };
                    let xr = &x[(iy * win.in_w + ix) * c..][..c];
                    let wr = &w[(ky * win.k_w + kx) * c..][..c];
                    for ((o, &xv), &wv) in out.iter_mut().zip(xr).zip(wr) {
                        *o += xv * wv;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tflite::Padding;

    #[test]
    fn single_channel_box_filter_counts_valid_taps() {
        // All-ones input and kernel: each output counts its in-bounds taps (+ bias).
        let win = Window::new(4, 5, [3, 3], [1, 1], Padding::Same);
        let x = vec![1.0; 4 * 5 * 2];
        let w = vec![1.0; 9 * 2];
        let b = [0.5, -1.0];
        let mut y = vec![0.0; 4 * 5 * 2];
        depthwise_conv2d(&x, &win, 2, &w, &b, &mut y);
        assert_eq!(y[0], 4.5); // corner: 2×2 taps
        assert_eq!(y[1], 3.0);
        assert_eq!(y[(5 + 1) * 2], 9.5); // interior
        assert_eq!(y[(5 + 4) * 2], 6.5); // right edge, 3×2 taps
        let win2 = Window::new(4, 4, [3, 3], [2, 2], Padding::Same);
        let mut y2 = vec![0.0; 2 * 2];
        depthwise_conv2d(&vec![1.0; 16], &win2, 1, &[1.0; 9], &[0.0], &mut y2);
        // TF SAME with stride 2 on 4: pad 0 before, 1 after.
        assert_eq!(y2, vec![9.0, 6.0, 6.0, 4.0]);
    }
}
