#[cfg(target_arch = "x86_64")]
use super::row_sweep::Row3;
use super::{Madd, Window};

/// Depthwise 2-D convolution with depth multiplier 1, NHWC, as TFLite's `DEPTHWISE_CONV_2D`:
/// `y[oy, ox, c] = b[c] + Σ w[ky, kx, c] · x[oy·s + ky − pad, ox·s + kx − pad, c]` (zero outside).
///
/// `x` is `[in_h, in_w, C]`, `w` is `[k_h, k_w, C]` (TFLite's `[1, k_h, k_w, C]`), `b` is `[C]`,
/// `y` is `[out_h, out_w, C]`.
///
/// # Panics
/// If a slice length does not match the window and channel count.
#[track_caller]
#[inline(always)]
pub fn depthwise_conv2d<M: Madd>(
    x: &[f32],
    win: &Window,
    c: usize,
    w: &[f32],
    b: &[f32],
    y: &mut [f32],
) {
    assert_eq!(x.len(), win.in_h * win.in_w * c, "depthwise input size");
    assert_eq!(y.len(), win.out_h * win.out_w * c, "depthwise output size");
    assert_eq!(w.len(), win.k_h * win.k_w * c, "depthwise kernel size");
    assert_eq!(b.len(), c, "depthwise bias size");
    // Output columns whose 3×3 window lies inside the input: `interior_row3` handles them with
    // the kernel held in registers; the other pixels go through `pixel`.
    let (ox_lo, ox_hi) = if win.k_h == 3 && win.k_w == 3 {
        let lo = win.pad_left.div_ceil(win.stride_w);
        let hi = (win.in_w + win.pad_left)
            .checked_sub(3)
            .map_or(0, |last| last / win.stride_w + 1)
            .min(win.out_w);
        (lo.min(hi), hi)
    } else {
        (0, 0)
    };
    // The row sweep's explicit AVX2 kernel, for fused multiply-adds only (see `Madd::FUSED`).
    #[cfg(target_arch = "x86_64")]
    let avx2 = M::FUSED
        && std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("fma");
    #[cfg(target_arch = "x86_64")]
    let avx512 = M::FUSED && super::avx512::available();
    for oy in 0..win.out_h {
        // Valid taps of this row: ky with 0 ≤ oy·s + ky − pad < in_h.
        let (ky0, ky1) = valid_taps(oy, win.stride_h, win.pad_top, win.k_h, win.in_h);
        let full_rows = win.k_h == 3 && ky0 == 0 && ky1 == 3;
        let (lo, hi) = if full_rows { (ox_lo, ox_hi) } else { (0, 0) };
        for ox in (0..lo).chain(hi.max(lo)..win.out_w) {
            #[cfg(target_arch = "x86_64")]
            if avx512 {
                let (kx0, kx1) = valid_taps(ox, win.stride_w, win.pad_left, win.k_w, win.in_w);
                let iy = oy * win.stride_h + ky0 - win.pad_top;
                let ix = ox * win.stride_w + kx0 - win.pad_left;
                let at = super::avx512::Taps {
                    x0: (iy * win.in_w + ix) * c,
                    row: win.in_w * c,
                    ky: (ky0, ky1),
                    kx: (kx0, kx1),
                    k_w: win.k_w,
                    y0: (oy * win.out_w + ox) * c,
                };
                // SAFETY: `avx512` is set only where the CPU has AVX-512F.
                #[allow(unsafe_code)]
                unsafe {
                    super::avx512::depthwise_pixel(x, w, b, &at, y)
                };
                continue;
            }
            pixel::<M>(x, win, c, w, b, oy, ox, (ky0, ky1), y);
        }
        if hi > lo {
            let iy0 = oy * win.stride_h - win.pad_top;
            #[cfg(target_arch = "x86_64")]
            if avx512 {
                let at = Row3 {
                    row: win.in_w * c,
                    step: win.stride_w * c,
                    x0: iy0 * win.in_w * c + (lo * win.stride_w - win.pad_left) * c,
                    y0: (oy * win.out_w + lo) * c,
                    n: hi - lo,
                };
                // SAFETY: `avx512` is set only where the CPU has AVX-512F.
                #[allow(unsafe_code)]
                unsafe {
                    super::avx512::depthwise_row3(x, w, b, &at, y)
                };
                continue;
            }
            let mut cb = 0;
            #[cfg(target_arch = "x86_64")]
            if avx2 {
                let row = win.in_w * c;
                let base = iy0 * row + (lo * win.stride_w - win.pad_left) * c;
                let o = (oy * win.out_w + lo) * c;
                while cb + 8 <= c {
                    let at = Row3 {
                        row,
                        step: win.stride_w * c,
                        x0: base + cb,
                        y0: o + cb,
                        n: hi - lo,
                    };
                    // SAFETY: `avx2` is set only where the CPU has AVX2 and FMA.
                    #[allow(unsafe_code)]
                    unsafe {
                        avx2::interior_row3_x8(x, w, b, c, cb, &at, y)
                    };
                    cb += 8;
                }
            }
            while cb + 8 <= c {
                interior_row3::<M, 8>(x, w, b, win, c, cb, iy0, (lo, hi), oy, y);
                cb += 8;
            }
            while cb + 4 <= c {
                interior_row3::<M, 4>(x, w, b, win, c, cb, iy0, (lo, hi), oy, y);
                cb += 4;
            }
            while cb < c {
                interior_row3::<M, 1>(x, w, b, win, c, cb, iy0, (lo, hi), oy, y);
                cb += 1;
            }
        }
    }
}

/// One output pixel, any window, taps clipped to the input.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn pixel<M: Madd>(
    x: &[f32],
    win: &Window,
    c: usize,
    w: &[f32],
    b: &[f32],
    oy: usize,
    ox: usize,
    (ky0, ky1): (usize, usize),
    y: &mut [f32],
) {
    let (kx0, kx1) = valid_taps(ox, win.stride_w, win.pad_left, win.k_w, win.in_w);
    let out = &mut y[(oy * win.out_w + ox) * c..][..c];
    let base_y = oy * win.stride_h + ky0 - win.pad_top;
    let base_x = ox * win.stride_w + kx0 - win.pad_left;
    let taps = (ky0, ky1, kx0, kx1);
    let mut cb = 0;
    while cb + 16 <= c {
        tap_block::<M, 16>(x, w, b, win, c, cb, taps, (base_y, base_x), out);
        cb += 16;
    }
    while cb + 4 <= c {
        tap_block::<M, 4>(x, w, b, win, c, cb, taps, (base_y, base_x), out);
        cb += 4;
    }
    while cb < c {
        tap_block::<M, 1>(x, w, b, win, c, cb, taps, (base_y, base_x), out);
        cb += 1;
    }
}

/// Channels `cb .. cb + NB` of output columns `lo .. hi` of row `oy`, every 3×3 tap inside the
/// input (top-left input row `iy0`): the nine weight vectors and the bias stay in registers
/// while the row is swept.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn interior_row3<M: Madd, const NB: usize>(
    x: &[f32],
    w: &[f32],
    b: &[f32],
    win: &Window,
    c: usize,
    cb: usize,
    iy0: usize,
    (lo, hi): (usize, usize),
    oy: usize,
    y: &mut [f32],
) {
    let wk: [[f32; NB]; 9] = std::array::from_fn(|t| std::array::from_fn(|j| w[t * c + cb + j]));
    let bias: [f32; NB] = std::array::from_fn(|j| b[cb + j]);
    let row = win.in_w * c;
    for ox in lo..hi {
        let ix0 = ox * win.stride_w - win.pad_left;
        let base = iy0 * row + ix0 * c + cb;
        let mut acc = bias;
        for ky in 0..3 {
            for kx in 0..3 {
                let xi = base + ky * row + kx * c;
                let xr: &[f32; NB] = x[xi..xi + NB].try_into().unwrap_or(&[0.0; NB]);
                let wr = &wk[ky * 3 + kx];
                for j in 0..NB {
                    acc[j] = M::madd(xr[j], wr[j], acc[j]);
                }
            }
        }
        let o = (oy * win.out_w + ox) * c + cb;
        y[o..o + NB].copy_from_slice(&acc);
    }
}

/// [`interior_row3`] for eight channels with AVX2 and FMA: six output columns at a time, so
/// that six independent multiply-add chains hide each one's latency (the compiler's version of
/// the generic kernel keeps one chain of nine dependent multiply-adds, a quarter of the CPU's
/// throughput, and spills registers when told to keep four).
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod avx2 {
    use crate::ops::row_sweep::Row3;
    use std::arch::x86_64::{__m256, _mm256_fmadd_ps, _mm256_loadu_ps, _mm256_storeu_ps};

    /// Output columns per block: six accumulators and the nine weight vectors stay in the
    /// sixteen registers (FaceMesh's depthwise layers with AVX2: 414 µs with four columns,
    /// 308–322 µs with five to eight; a block of three for the remainder made it 343 µs).
    const COLUMNS: usize = 6;

    /// Channels `cb .. cb + 8` of `at.n` output columns (`c` channels per pixel).
    ///
    /// # Panics
    /// If a read or write would leave `x`, `w`, `b` or `y`.
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn interior_row3_x8(
        x: &[f32],
        w: &[f32],
        b: &[f32],
        c: usize,
        cb: usize,
        at: &Row3,
        y: &mut [f32],
    ) {
        if at.n == 0 {
            return;
        }
        let last = at.n - 1;
        assert!(at.x0 + last * at.step + 2 * at.row + 2 * c + 8 <= x.len());
        assert!(at.y0 + last * c + 8 <= y.len());
        assert!(8 * c + cb + 8 <= w.len() && cb + 8 <= b.len());
        let (xp, yp) = (x.as_ptr(), y.as_mut_ptr());
        // The asserts above bound the highest index each load and store below touches: tap
        // (2, 2) of the last column, the last column's output, weight tap 8.
        // SAFETY: `i` is a tap of a column below `at.n` (see above).
        let load = |i: usize| unsafe { _mm256_loadu_ps(xp.add(i)) };
        // SAFETY: `t·c + cb + 8 ≤ w.len()` for t ≤ 8, `cb + 8 ≤ b.len()` (asserted).
        let (wk, bias): ([__m256; 9], __m256) = unsafe {
            (
                std::array::from_fn(|t| _mm256_loadu_ps(w.as_ptr().add(t * c + cb))),
                _mm256_loadu_ps(b.as_ptr().add(cb)),
            )
        };
        let (row, step) = (at.row, at.step);
        let mut p = 0;
        // Blocks of `$n` columns while they last: `$n` independent multiply-add chains.
        macro_rules! sweep {
            ($n:expr) => {
                while at.n - p >= $n {
                    let xb = at.x0 + p * step;
                    let mut acc = [bias; $n];
                    for ky in 0..3 {
                        for kx in 0..3 {
                            let xi = xb + ky * row + kx * c;
                            let wv = wk[ky * 3 + kx];
                            for (q, a) in acc.iter_mut().enumerate() {
                                *a = _mm256_fmadd_ps(load(xi + q * step), wv, *a);
                            }
                        }
                    }
                    for (q, a) in acc.iter().enumerate() {
                        // SAFETY: column p + q < at.n (asserted bound on y).
                        unsafe { _mm256_storeu_ps(yp.add(at.y0 + (p + q) * c), *a) };
                    }
                    p += $n;
                }
            };
        }
        sweep!(COLUMNS);
        sweep!(1);
    }
}

/// Taps `k0 .. k1` of a window at output index `o` that fall inside `0 .. len`.
#[inline(always)]
pub(super) fn valid_taps(
    o: usize,
    stride: usize,
    pad: usize,
    k: usize,
    len: usize,
) -> (usize, usize) {
    let start = o * stride;
    let k0 = pad.saturating_sub(start).min(k);
    let k1 = (len + pad).saturating_sub(start).min(k).max(k0);
    (k0, k1)
}

/// Channels `cb .. cb + NB` of one output pixel, accumulated in registers.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn tap_block<M: Madd, const NB: usize>(
    x: &[f32],
    w: &[f32],
    b: &[f32],
    win: &Window,
    c: usize,
    cb: usize,
    (ky0, ky1, kx0, kx1): (usize, usize, usize, usize),
    (base_y, base_x): (usize, usize),
    out: &mut [f32],
) {
    let mut acc: [f32; NB] = b[cb..cb + NB].try_into().unwrap_or([0.0; NB]);
    for ky in ky0..ky1 {
        let iy = base_y + ky - ky0;
        for kx in kx0..kx1 {
            let ix = base_x + kx - kx0;
            let xi = (iy * win.in_w + ix) * c + cb;
            let wi = (ky * win.k_w + kx) * c + cb;
            let xr: &[f32; NB] = x[xi..xi + NB].try_into().unwrap_or(&[0.0; NB]);
            let wr: &[f32; NB] = w[wi..wi + NB].try_into().unwrap_or(&[0.0; NB]);
            for j in 0..NB {
                acc[j] = M::madd(xr[j], wr[j], acc[j]);
            }
        }
    }
    out[cb..cb + NB].copy_from_slice(&acc);
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
        depthwise_conv2d::<crate::ops::Plain>(&x, &win, 2, &w, &b, &mut y);
        assert_eq!(y[0], 4.5); // corner: 2×2 taps
        assert_eq!(y[1], 3.0);
        assert_eq!(y[(5 + 1) * 2], 9.5); // interior
        assert_eq!(y[(5 + 4) * 2], 6.5); // right edge, 3×2 taps
        let win2 = Window::new(4, 4, [3, 3], [2, 2], Padding::Same);
        let mut y2 = vec![0.0; 2 * 2];
        depthwise_conv2d::<crate::ops::Fused>(&[1.0; 16], &win2, 1, &[1.0; 9], &[0.0], &mut y2);
        // TF SAME with stride 2 on 4: pad 0 before, 1 after.
        assert_eq!(y2, vec![9.0, 6.0, 6.0, 4.0]);
    }

    #[test]
    fn matches_direct_definition_on_many_channels() {
        // Both roundings (the fused one takes the AVX2 row kernel where the CPU has it); widths
        // give row sweeps with whole groups of six columns and a remainder, channel counts
        // whole blocks of eight and a remainder.
        let mut seed = 7u32;
        let mut rnd = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5
        };
        let shapes = [
            (6, 7, 24, 1),
            (8, 8, 21, 2),
            (5, 5, 36, 1),
            (4, 9, 3, 1),
            (7, 13, 40, 2),
            (5, 14, 19, 1),
            (4, 11, 16, 1),
        ];
        for (&(h, w, c, s), fused) in shapes.iter().flat_map(|t| [(t, false), (t, true)]) {
            let win = Window::new(h, w, [3, 3], [s, s], Padding::Same);
            let x: Vec<f32> = (0..h * w * c).map(|_| rnd()).collect();
            let k: Vec<f32> = (0..9 * c).map(|_| rnd()).collect();
            let b: Vec<f32> = (0..c).map(|_| rnd()).collect();
            let mut y = vec![0.0; win.out_h * win.out_w * c];
            if fused {
                depthwise_conv2d::<crate::ops::Fused>(&x, &win, c, &k, &b, &mut y);
                // The AVX-512 kernels (where the CPU has them) and the AVX2 and generic ones:
                // the same values bit for bit.
                #[cfg(target_arch = "x86_64")]
                {
                    let mut y2 = vec![0.0; y.len()];
                    crate::ops::avx512::without(|| {
                        depthwise_conv2d::<crate::ops::Fused>(&x, &win, c, &k, &b, &mut y2)
                    });
                    for (p, q) in y.iter().zip(&y2) {
                        assert_eq!(p.to_bits(), q.to_bits(), "{h}x{w}x{c} s{s}");
                    }
                }
            } else {
                depthwise_conv2d::<crate::ops::Plain>(&x, &win, c, &k, &b, &mut y);
            }
            for oy in 0..win.out_h {
                for ox in 0..win.out_w {
                    for ch in 0..c {
                        let mut acc = b[ch] as f64;
                        for ky in 0..3 {
                            for kx in 0..3 {
                                let iy = (oy * s + ky) as isize - win.pad_top as isize;
                                let ix = (ox * s + kx) as isize - win.pad_left as isize;
                                if iy >= 0 && ix >= 0 && (iy as usize) < h && (ix as usize) < w {
                                    acc += x[((iy as usize) * w + ix as usize) * c + ch] as f64
                                        * k[(ky * 3 + kx) * c + ch] as f64;
                                }
                            }
                        }
                        let got = y[(oy * win.out_w + ox) * c + ch] as f64;
                        assert!(
                            (got - acc).abs() < 1e-5,
                            "{h}x{w}x{c} s{s} fused {fused} at ({oy},{ox},{ch}): {got} vs {acc}"
                        );
                    }
                }
            }
        }
    }
}
