use super::Window;

/// Max pooling over `k_h × k_w` windows, NHWC (TFLite `MAX_POOL_2D`; padded taps are ignored).
///
/// `x` is `[in_h, in_w, C]`, `y` is `[out_h, out_w, C]`.
///
/// # Panics
/// If a slice length does not match the window and channel count.
#[track_caller]
#[inline(always)]
pub fn max_pool2d(x: &[f32], win: &Window, c: usize, y: &mut [f32]) {
    assert_eq!(x.len(), win.in_h * win.in_w * c, "max_pool input size");
    assert_eq!(y.len(), win.out_h * win.out_w * c, "max_pool output size");
    for oy in 0..win.out_h {
        for ox in 0..win.out_w {
            let out = &mut y[(oy * win.out_w + ox) * c..][..c];
            out.fill(f32::NEG_INFINITY);
            for ky in 0..win.k_h {
                let Some(iy) = Window::tap(oy, win.stride_h, ky, win.pad_top, win.in_h) else {
                    continue;
                };
                for kx in 0..win.k_w {
                    let Some(ix) = Window::tap(ox, win.stride_w, kx, win.pad_left, win.in_w) else {
                        continue;
                    };
                    for (o, &v) in out.iter_mut().zip(&x[(iy * win.in_w + ix) * c..][..c]) {
                        *o = o.max(v);
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
    fn two_by_two_stride_two() {
        let win = Window::new(2, 4, [2, 2], [2, 2], Padding::Valid);
        let x = [1.0, 5.0, 2.0, 0.0, -1.0, 3.0, 7.0, 8.0];
        let mut y = [0.0; 2];
        max_pool2d(&x, &win, 1, &mut y);
        assert_eq!(y, [5.0, 8.0]);
    }

    #[test]
    fn matches_direct_definition_with_padding() {
        // Windows clipped at every border (SAME padding, odd sizes), a few channels.
        for &(h, w, c, k, st) in &[(5, 7, 3, 3, 2), (6, 6, 16, 2, 2), (4, 9, 5, 3, 1)] {
            let win = Window::new(h, w, [k, k], [st, st], Padding::Same);
            let x = crate::ops::test_values(h * w * c, 11);
            let mut y = vec![0.0; win.out_h * win.out_w * c];
            max_pool2d(&x, &win, c, &mut y);
            for oy in 0..win.out_h {
                for ox in 0..win.out_w {
                    for ch in 0..c {
                        let mut m = f32::NEG_INFINITY;
                        for ky in 0..k {
                            for kx in 0..k {
                                let iy = (oy * st + ky) as isize - win.pad_top as isize;
                                let ix = (ox * st + kx) as isize - win.pad_left as isize;
                                if iy >= 0 && ix >= 0 && (iy as usize) < h && (ix as usize) < w {
                                    m = m.max(x[((iy as usize) * w + ix as usize) * c + ch]);
                                }
                            }
                        }
                        assert_eq!(y[(oy * win.out_w + ox) * c + ch], m, "{h}x{w}x{c} k{k}");
                    }
                }
            }
        }
    }
}
