use super::Window;

/// Convolution weights re-laid out for the NHWC kernel: `w[(ky·k_w + kx)·C_in + ci][co]`
/// (the reduction index outer, output channels contiguous), plus the bias `[C_out]`.
#[derive(Clone, Debug)]
pub struct Conv2dWeights {
    pub c_in: usize,
    pub c_out: usize,
    pub w: Vec<f32>,
    pub bias: Vec<f32>,
}

impl Conv2dWeights {
    /// From TFLite's `[C_out, k_h, k_w, C_in]` kernel.
    pub fn from_ohwi(
        ohwi: &[f32],
        c_out: usize,
        k_h: usize,
        k_w: usize,
        c_in: usize,
        bias: Vec<f32>,
    ) -> Self {
        let red = k_h * k_w * c_in;
        let mut w = vec![0.0; red * c_out];
        for o in 0..c_out {
            for r in 0..red {
                w[r * c_out + o] = ohwi[o * red + r];
            }
        }
        Conv2dWeights {
            c_in,
            c_out,
            w,
            bias,
        }
    }
}

/// Dense 2-D convolution, NHWC, no dilation: `y[oy, ox, co] = b[co] + Σ w[ky, kx, ci, co] ·
/// x[oy·s + ky − pad, ox·s + kx − pad, ci]` (zero outside the input), as TFLite's `CONV_2D`.
///
/// `x` is `[in_h, in_w, C_in]`, `y` is `[out_h, out_w, C_out]`; `patch` is scratch of
/// `k_h·k_w·C_in` values. A 1×1 stride-1 convolution is a GEMM and reads `x` in place.
///
/// # Panics
/// If a slice length does not match the window and weights.
#[track_caller]
pub fn conv2d(x: &[f32], win: &Window, wts: &Conv2dWeights, patch: &mut [f32], y: &mut [f32]) {
    let (ci, co) = (wts.c_in, wts.c_out);
    let red = win.k_h * win.k_w * ci;
    assert_eq!(x.len(), win.in_h * win.in_w * ci, "conv2d input size");
    assert_eq!(y.len(), win.out_h * win.out_w * co, "conv2d output size");
    assert!(patch.len() >= red, "conv2d scratch too small");
    let pointwise = win.k_h == 1 && win.k_w == 1 && win.stride_h == 1 && win.stride_w == 1;
    if pointwise {
        // Four pixels at a time: every weight row is loaded once per four outputs.
        let mut rows = y.chunks_exact_mut(4 * co);
        let mut inputs = x.chunks_exact(4 * ci);
        for (yb, xb) in (&mut rows).zip(&mut inputs) {
            gemv4(xb, &wts.w, &wts.bias, ci, co, yb);
        }
        for (yr, xr) in rows
            .into_remainder()
            .chunks_exact_mut(co)
            .zip(inputs.remainder().chunks_exact(ci))
        {
            gemv(xr, &wts.w, &wts.bias, yr);
        }
        return;
    }
    let patch = &mut patch[..red];
    for oy in 0..win.out_h {
        for ox in 0..win.out_w {
            let mut p = 0;
            for ky in 0..win.k_h {
                let iy = Window::tap(oy, win.stride_h, ky, win.pad_top, win.in_h);
                for kx in 0..win.k_w {
                    let ix = Window::tap(ox, win.stride_w, kx, win.pad_left, win.in_w);
                    let dst = &mut patch[p..p + ci];
                    match (iy, ix) {
                        (Some(iy), Some(ix)) => {
                            dst.copy_from_slice(&x[(iy * win.in_w + ix) * ci..][..ci])
                        }
                        _ => dst.fill(0.0),
                    }
                    p += ci;
                }
            }
            let o = (oy * win.out_w + ox) * co;
            gemv(patch, &wts.w, &wts.bias, &mut y[o..o + co]);
        }
    }
}

/// `y = b + Σ_r a[r] · w[r, :]` with `w` row-major `[len(a), len(y)]`.
#[inline(always)]
fn gemv(a: &[f32], w: &[f32], b: &[f32], y: &mut [f32]) {
    let co = y.len();
    y.copy_from_slice(b);
    for (&ar, wr) in a.iter().zip(w.chunks_exact(co)) {
        for (yo, &wo) in y.iter_mut().zip(wr) {
            *yo += ar * wo;
        }
    }
}

/// [`gemv`] for four input rows `a` (`4 × ci`) into four output rows `y` (`4 × co`).
#[inline(always)]
fn gemv4(a: &[f32], w: &[f32], b: &[f32], ci: usize, co: usize, y: &mut [f32]) {
    let (y0, rest) = y.split_at_mut(co);
    let (y1, rest) = rest.split_at_mut(co);
    let (y2, y3) = rest.split_at_mut(co);
    y0.copy_from_slice(b);
    y1.copy_from_slice(b);
    y2.copy_from_slice(b);
    y3.copy_from_slice(b);
    for (r, wr) in w.chunks_exact(co).enumerate().take(ci) {
        let (a0, a1, a2, a3) = (a[r], a[ci + r], a[2 * ci + r], a[3 * ci + r]);
        for ((((o0, o1), o2), o3), &wo) in y0
            .iter_mut()
            .zip(y1.iter_mut())
            .zip(y2.iter_mut())
            .zip(y3.iter_mut())
            .zip(wr)
        {
            *o0 += a0 * wo;
            *o1 += a1 * wo;
            *o2 += a2 * wo;
            *o3 += a3 * wo;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tflite::Padding;

    /// Direct definition, f64, for comparison.
    fn reference(
        x: &[f32],
        win: &Window,
        ohwi: &[f32],
        b: &[f32],
        ci: usize,
        co: usize,
    ) -> Vec<f32> {
        let mut y = vec![0.0; win.out_h * win.out_w * co];
        for oy in 0..win.out_h {
            for ox in 0..win.out_w {
                for o in 0..co {
                    let mut s = b[o] as f64;
                    for ky in 0..win.k_h {
                        for kx in 0..win.k_w {
                            let iy = (oy * win.stride_h + ky) as isize - win.pad_top as isize;
                            let ix = (ox * win.stride_w + kx) as isize - win.pad_left as isize;
                            if iy < 0
                                || ix < 0
                                || iy >= win.in_h as isize
                                || ix >= win.in_w as isize
                            {
                                continue;
                            }
                            for c in 0..ci {
                                let xv =
                                    x[((iy as usize) * win.in_w + ix as usize) * ci + c] as f64;
                                s += xv * ohwi[((o * win.k_h + ky) * win.k_w + kx) * ci + c] as f64;
                            }
                        }
                    }
                    y[(oy * win.out_w + ox) * co + o] = s as f32;
                }
            }
        }
        y
    }

    fn pseudo(n: usize, seed: u32) -> Vec<f32> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (s >> 8) as f32 / (1u32 << 24) as f32 - 0.5
            })
            .collect()
    }

    #[test]
    fn matches_direct_definition() {
        for &(h, w, ci, co, k, s, pad) in &[
            (7, 5, 3, 4, 3, 2, Padding::Same),
            (8, 8, 3, 5, 5, 2, Padding::Same),
            (9, 6, 5, 7, 1, 1, Padding::Same),
            (3, 3, 4, 6, 3, 3, Padding::Valid),
            (6, 6, 2, 3, 3, 1, Padding::Same),
        ] {
            let win = Window::new(h, w, [k, k], [s, s], pad);
            let x = pseudo(h * w * ci, 1);
            let ohwi = pseudo(co * k * k * ci, 2);
            let b = pseudo(co, 3);
            let wts = Conv2dWeights::from_ohwi(&ohwi, co, k, k, ci, b.clone());
            let mut y = vec![0.0; win.out_h * win.out_w * co];
            let mut patch = vec![0.0; k * k * ci];
            conv2d(&x, &win, &wts, &mut patch, &mut y);
            let r = reference(&x, &win, &ohwi, &b, ci, co);
            for (a, b) in y.iter().zip(&r) {
                assert!(
                    (a - b).abs() < 1e-5,
                    "{a} vs {b} for {h}x{w}x{ci}->{co} k{k} s{s}"
                );
            }
        }
    }
}
