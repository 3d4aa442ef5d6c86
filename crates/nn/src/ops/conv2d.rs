use super::depthwise_conv2d::valid_taps;
use super::{Activation, Madd, Window};

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
/// `k_h·k_w·C_in` values (one border pixel's window). A 1×1 stride-1 convolution is a GEMM and reads `x` in place.
/// `act` is the fused activation, applied to the register block before it is stored.
///
/// # Panics
/// If a slice length does not match the window and weights.
#[track_caller]
#[inline(always)]
pub fn conv2d<M: Madd>(
    x: &[f32],
    win: &Window,
    wts: &Conv2dWeights,
    act: Activation,
    patch: &mut [f32],
    y: &mut [f32],
) {
    // A flag tested once per register block, not a second copy of the loops: the kernels are
    // inlined into the network's step loop, and a second copy there made LLVM compile the plain
    // one less well (about 4 % more instructions for the networks without activations).
    let relu = act == Activation::Relu;
    let (ci, co) = (wts.c_in, wts.c_out);
    let red = win.k_h * win.k_w * ci;
    assert_eq!(x.len(), win.in_h * win.in_w * ci, "conv2d input size");
    assert_eq!(y.len(), win.out_h * win.out_w * co, "conv2d output size");
    assert!(patch.len() >= red, "conv2d scratch too small");
    let pointwise = win.k_h == 1 && win.k_w == 1 && win.stride_h == 1 && win.stride_w == 1;
    if pointwise {
        // A GEMM `[pixels, C_in] × [C_in, C_out]`, ROWS pixels at a time.
        let mut rows = y.chunks_exact_mut(ROWS * co);
        let mut inputs = x.chunks_exact(ROWS * ci);
        for (yb, xb) in (&mut rows).zip(&mut inputs) {
            gemm_rows::<M, ROWS>(xb, red, &wts.w, &wts.bias, relu, yb);
        }
        for (yr, xr) in rows
            .into_remainder()
            .chunks_exact_mut(co)
            .zip(inputs.remainder().chunks_exact(ci))
        {
            gemm_rows::<M, 1>(xr, red, &wts.w, &wts.bias, relu, yr);
        }
        return;
    }
    // Per output row: the pixels whose whole window lies inside the input read it in place
    // (`direct_rows`, ROWS pixels at a time); the others are gathered into `patch` first
    // (im2col, zeros in the padding) for the GEMM micro-kernel.
    let lo = win.pad_left.div_ceil(win.stride_w).min(win.out_w);
    let hi = (win.in_w + win.pad_left)
        .checked_sub(win.k_w)
        .map_or(0, |last| last / win.stride_w + 1)
        .min(win.out_w)
        .max(lo);
    for oy in 0..win.out_h {
        let (ky0, ky1) = valid_taps(oy, win.stride_h, win.pad_top, win.k_h, win.in_h);
        let (lo, hi) = if ky0 == 0 && ky1 == win.k_h {
            (lo, hi)
        } else {
            (0, 0)
        };
        for ox in (0..lo).chain(hi..win.out_w) {
            let dst = &mut patch[..red];
            gather(x, win, ci, oy, ox, dst);
            let o = (oy * win.out_w + ox) * co;
            gemm_rows::<M, 1>(dst, red, &wts.w, &wts.bias, relu, &mut y[o..o + co]);
        }
        if lo == hi {
            continue;
        }
        // Every kernel row is inside the input here, so the window's top row is too.
        let iy0 = oy * win.stride_h - win.pad_top;
        let mut ox = lo;
        while ox < hi {
            let base = (iy0 * win.in_w + ox * win.stride_w - win.pad_left) * ci;
            let o = (oy * win.out_w + ox) * co;
            if ox + ROWS <= hi {
                direct_rows::<M, ROWS>(x, win, ci, base, &wts.w, &wts.bias, relu, &mut y[o..]);
                ox += ROWS;
            } else {
                direct_rows::<M, 1>(x, win, ci, base, &wts.w, &wts.bias, relu, &mut y[o..]);
                ox += 1;
            }
        }
    }
}

/// The window of output pixel `(oy, ox)` as one row of `k_h·k_w·C_in` values (zero in the
/// padding) into `dst`.
#[inline(always)]
fn gather(x: &[f32], win: &Window, ci: usize, oy: usize, ox: usize, dst: &mut [f32]) {
    // Per kernel row, the valid taps are one contiguous run of the input row.
    let (kx0, kx1) = valid_taps(ox, win.stride_w, win.pad_left, win.k_w, win.in_w);
    for ky in 0..win.k_h {
        let row = &mut dst[ky * win.k_w * ci..(ky + 1) * win.k_w * ci];
        match Window::tap(oy, win.stride_h, ky, win.pad_top, win.in_h) {
            Some(iy) if kx1 > kx0 => {
                let ix0 = ox * win.stride_w + kx0 - win.pad_left;
                row[..kx0 * ci].fill(0.0);
                row[kx0 * ci..kx1 * ci].copy_from_slice(
                    &x[(iy * win.in_w + ix0) * ci..(iy * win.in_w + ix0 + kx1 - kx0) * ci],
                );
                row[kx1 * ci..].fill(0.0);
            }
            _ => row.fill(0.0),
        }
    }
}

/// [`gemm_rows`] for `R` neighbouring output pixels of one row whose windows lie inside the
/// input, read in place: pixel `p`'s window starts at `x[base + p·stride_w·C_in]`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn direct_rows<M: Madd, const R: usize>(
    x: &[f32],
    win: &Window,
    ci: usize,
    base: usize,
    w: &[f32],
    b: &[f32],
    relu: bool,
    y: &mut [f32],
) {
    let co = b.len();
    let mut ob = 0;
    while ob + 16 <= co {
        direct_block::<M, R, 16>(x, win, ci, base, w, b, ob, relu, y);
        ob += 16;
    }
    if ob + 8 <= co {
        direct_block::<M, R, 8>(x, win, ci, base, w, b, ob, relu, y);
        ob += 8;
    }
    if ob + 4 <= co {
        direct_block::<M, R, 4>(x, win, ci, base, w, b, ob, relu, y);
        ob += 4;
    }
    while ob < co {
        direct_block::<M, R, 1>(x, win, ci, base, w, b, ob, relu, y);
        ob += 1;
    }
}

/// One `R × NB` register block of [`direct_rows`], output channels `ob .. ob + NB`; the taps go
/// in the weights' order `(ky, kx, c)`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn direct_block<M: Madd, const R: usize, const NB: usize>(
    x: &[f32],
    win: &Window,
    ci: usize,
    base: usize,
    w: &[f32],
    b: &[f32],
    ob: usize,
    relu: bool,
    y: &mut [f32],
) {
    let co = b.len();
    let step = win.stride_w * ci;
    let run = win.k_w * ci;
    let mut acc = [[0.0f32; NB]; R];
    let bias: &[f32; NB] = b[ob..ob + NB].try_into().unwrap_or(&[0.0; NB]);
    for row in acc.iter_mut() {
        *row = *bias;
    }
    for ky in 0..win.k_h {
        // Within a kernel row the taps (kx, c) are contiguous in the input.
        let start = base + ky * win.in_w * ci;
        let starts: [usize; R] = std::array::from_fn(|p| start + p * step);
        let wk = &w[ky * run * co..];
        for t in 0..run {
            let wr: &[f32; NB] = wk[t * co + ob..t * co + ob + NB]
                .try_into()
                .unwrap_or(&[0.0; NB]);
            for (row, &s0) in acc.iter_mut().zip(&starts) {
                let ap = x[s0 + t];
                for j in 0..NB {
                    row[j] = M::madd(ap, wr[j], row[j]);
                }
            }
        }
    }
    if relu {
        for row in acc.iter_mut() {
            for v in row.iter_mut() {
                *v = v.max(0.0);
            }
        }
    }
    for (p, row) in acc.iter().enumerate() {
        y[p * co + ob..p * co + ob + NB].copy_from_slice(row);
    }
}

/// Pixels per micro-kernel call.
const ROWS: usize = 4;

/// `y[p, :] = b + Σ_r a[p, r] · w[r, :]` for `R` rows (then `max(·, 0)` if `relu`): `a` is
/// `R × red`, `w` is `red × C_out`, `y` is `R × C_out`. Output channels go in register blocks of
/// 16, then 8, then 4, then one by one.
#[inline(always)]
fn gemm_rows<M: Madd, const R: usize>(
    a: &[f32],
    red: usize,
    w: &[f32],
    b: &[f32],
    relu: bool,
    y: &mut [f32],
) {
    let co = b.len();
    let mut ob = 0;
    while ob + 16 <= co {
        block::<M, R, 16>(a, red, w, b, co, ob, relu, y);
        ob += 16;
    }
    if ob + 8 <= co {
        block::<M, R, 8>(a, red, w, b, co, ob, relu, y);
        ob += 8;
    }
    if ob + 4 <= co {
        block::<M, R, 4>(a, red, w, b, co, ob, relu, y);
        ob += 4;
    }
    while ob < co {
        block::<M, R, 1>(a, red, w, b, co, ob, relu, y);
        ob += 1;
    }
}

/// One `R × NB` register block of [`gemm_rows`], output channels `ob .. ob + NB`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn block<M: Madd, const R: usize, const NB: usize>(
    a: &[f32],
    red: usize,
    w: &[f32],
    b: &[f32],
    co: usize,
    ob: usize,
    relu: bool,
    y: &mut [f32],
) {
    let mut acc = [[0.0f32; NB]; R];
    let bias: &[f32; NB] = b[ob..ob + NB].try_into().unwrap_or(&[0.0; NB]);
    for row in acc.iter_mut() {
        *row = *bias;
    }
    for r in 0..red {
        let wr: &[f32; NB] = w[r * co + ob..r * co + ob + NB]
            .try_into()
            .unwrap_or(&[0.0; NB]);
        for (p, row) in acc.iter_mut().enumerate() {
            let ap = a[p * red + r];
            for j in 0..NB {
                row[j] = M::madd(ap, wr[j], row[j]);
            }
        }
    }
    if relu {
        for row in acc.iter_mut() {
            for v in row.iter_mut() {
                *v = v.max(0.0);
            }
        }
    }
    for (p, row) in acc.iter().enumerate() {
        y[p * co + ob..p * co + ob + NB].copy_from_slice(row);
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
            (5, 7, 9, 29, 1, 1, Padding::Same),
            (4, 4, 6, 40, 3, 1, Padding::Same),
            (3, 3, 4, 6, 3, 3, Padding::Valid),
            (6, 6, 2, 3, 3, 1, Padding::Same),
            // Rows with enough interior pixels for whole in-place blocks and a remainder.
            (6, 13, 3, 20, 3, 1, Padding::Same),
            (9, 17, 4, 24, 3, 2, Padding::Same),
            (7, 12, 2, 9, 3, 1, Padding::Valid),
        ] {
            let win = Window::new(h, w, [k, k], [s, s], pad);
            let x = pseudo(h * w * ci, 1);
            let ohwi = pseudo(co * k * k * ci, 2);
            let b = pseudo(co, 3);
            let wts = Conv2dWeights::from_ohwi(&ohwi, co, k, k, ci, b.clone());
            let mut y = vec![0.0; win.out_h * win.out_w * co];
            let mut patch = vec![0.0; ROWS * k * k * ci];
            conv2d::<crate::ops::Plain>(&x, &win, &wts, Activation::None, &mut patch, &mut y);
            let mut y2 = vec![0.0; y.len()];
            conv2d::<crate::ops::Fused>(&x, &win, &wts, Activation::None, &mut patch, &mut y2);
            for (a, b) in y.iter().zip(&y2) {
                assert!((a - b).abs() < 1e-5);
            }
            let r = reference(&x, &win, &ohwi, &b, ci, co);
            for (a, b) in y.iter().zip(&r) {
                assert!(
                    (a - b).abs() < 1e-5,
                    "{a} vs {b} for {h}x{w}x{ci}->{co} k{k} s{s}"
                );
            }
            // The fused ReLU is max(·, 0) of the same values, bit for bit.
            let mut y3 = vec![0.0; y.len()];
            conv2d::<crate::ops::Plain>(&x, &win, &wts, Activation::Relu, &mut patch, &mut y3);
            for (a, b) in y3.iter().zip(&y) {
                assert_eq!(a.to_bits(), b.max(0.0).to_bits());
            }
        }
    }

    #[test]
    fn fused_relu_by_hand() {
        // 1×1 conv of a 1×2×1 input [1, −2] with weights [1, −1] (2 outputs), bias [0.5, 0]:
        // pixel 0 → (1.5, −1) → ReLU (1.5, 0); pixel 1 → (−1.5, 2) → (0, 2).
        let win = Window::new(1, 2, [1, 1], [1, 1], Padding::Same);
        let wts = Conv2dWeights::from_ohwi(&[1.0, -1.0], 2, 1, 1, 1, vec![0.5, 0.0]);
        let mut y = [9.0; 4];
        let mut patch = vec![0.0; ROWS];
        conv2d::<crate::ops::Plain>(
            &[1.0, -2.0],
            &win,
            &wts,
            Activation::Relu,
            &mut patch,
            &mut y,
        );
        assert_eq!(y, [1.5, 0.0, 0.0, 2.0]);
        conv2d::<crate::ops::Plain>(
            &[1.0, -2.0],
            &win,
            &wts,
            Activation::None,
            &mut patch,
            &mut y,
        );
        assert_eq!(y, [1.5, -1.0, -1.5, 2.0]);
    }
}
