use super::depthwise_conv2d::valid_taps;
use super::{Activation, Madd, Window};

/// Convolution weights re-laid out for the NHWC kernel: `w[(ky·k_w + kx)·C_in + ci][co]`
/// (the reduction index outer, output channels contiguous), plus the bias `[C_out]`; on x86-64
/// CPUs with AVX-512 also in the panels its kernel streams.
#[derive(Clone, Debug)]
pub struct Conv2dWeights {
    pub c_in: usize,
    pub c_out: usize,
    pub w: Vec<f32>,
    pub bias: Vec<f32>,
    /// `w` in panels of output channels for the AVX-512 kernel (empty where it does not run).
    panels: Vec<f32>,
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
        #[cfg(target_arch = "x86_64")]
        let panels = if super::avx512::available() {
            super::avx512::pack(&w, red, c_out)
        } else {
            Vec::new()
        };
        #[cfg(not(target_arch = "x86_64"))]
        let panels = Vec::new();
        Conv2dWeights {
            c_in,
            c_out,
            w,
            bias,
            panels,
        }
    }
}

/// Dense 2-D convolution, NHWC, no dilation: `y[oy, ox, co] = b[co] + Σ w[ky, kx, ci, co] ·
/// x[oy·s + ky − pad, ox·s + kx − pad, ci]` (zero outside the input), as TFLite's `CONV_2D`.
///
/// `x` is `[in_h, in_w, C_in]`, `y` is `[out_h, out_w, C_out]`; `patch` is scratch of
/// [`conv2d_scratch_len`] values (the windows of the pixels gathered for one micro-kernel call). A 1×1
/// stride-1 convolution is a GEMM and reads `x` in place.
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
    assert!(
        patch.len() >= conv2d_scratch_len(win.k_h, win.k_w, ci),
        "conv2d scratch too small"
    );
    let pointwise = win.k_h == 1 && win.k_w == 1 && win.stride_h == 1 && win.stride_w == 1;
    // The AVX-512 kernel, for fused multiply-adds only (see `Madd::FUSED`).
    #[cfg(target_arch = "x86_64")]
    let avx512 = M::FUSED && super::avx512::available();
    if pointwise {
        #[cfg(target_arch = "x86_64")]
        if avx512 {
            let at = super::avx512::InPlace::contiguous(ci);
            // SAFETY: the CPU has AVX-512F (tested above).
            #[allow(unsafe_code)]
            unsafe {
                super::avx512::conv_rows(x, &at, x.len() / ci, &wts.panels, &wts.bias, relu, y, 0)
            };
            return;
        }
        // A GEMM `[pixels, C_in] × [C_in, C_out]`: with AVX2 and fused multiply-adds, blocks of
        // 16 output channels of `avx2::ROWS` pixels by explicit vector code, else ROWS pixels at
        // a time (see `Madd::FUSED`).
        #[cfg(target_arch = "x86_64")]
        let (x, y) = if M::FUSED
            && co >= 16
            && std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma")
        {
            let n = x.len() / ci / avx2::ROWS * avx2::ROWS;
            for (yb, xb) in y[..n * co]
                .chunks_exact_mut(avx2::ROWS * co)
                .zip(x[..n * ci].chunks_exact(avx2::ROWS * ci))
            {
                // SAFETY: the CPU has AVX2 and FMA (tested above).
                #[allow(unsafe_code)]
                unsafe {
                    avx2_rows::<M>(xb, red, wts, relu, yb)
                };
            }
            (&x[n * ci..], &mut y[n * co..])
        } else {
            (x, y)
        };
        let mut rows = y.chunks_exact_mut(ROWS * co);
        let mut inputs = x.chunks_exact(ROWS * ci);
        for (yb, xb) in (&mut rows).zip(&mut inputs) {
            gemm_rows::<M, ROWS>(xb, red, &wts.w, &wts.bias, 0, relu, yb);
        }
        for (yr, xr) in rows
            .into_remainder()
            .chunks_exact_mut(co)
            .zip(inputs.remainder().chunks_exact(ci))
        {
            gemm_rows::<M, 1>(xr, red, &wts.w, &wts.bias, 0, relu, yr);
        }
        return;
    }
    // With AVX2 and fused multiply-adds: every pixel's window gathered (zeros in the padding),
    // `avx2::ROWS` pixels at a time in raster order, for the GEMM kernel of the 1×1
    // convolutions. The taps are summed in the same order as below, so the outputs are the
    // same to the bit; the register blocks of the code below keep fewer pixels in flight, and
    // a 2 × 2 output had one pixel per call. Below 32 output channels the copies cost more
    // than they save (FaceMesh's first layer, 3 → 16 channels: 193 → 300 µs).
    #[cfg(target_arch = "x86_64")]
    if !avx512
        && M::FUSED
        && co >= 32
        && std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("fma")
    {
        let pixels = win.out_h * win.out_w;
        let n = pixels / avx2::ROWS * avx2::ROWS;
        let patch = &mut patch[..avx2::ROWS * red];
        for first in (0..n).step_by(avx2::ROWS) {
            for (p, dst) in patch.chunks_exact_mut(red).enumerate() {
                let i = first + p;
                gather(x, win, ci, i / win.out_w, i % win.out_w, dst);
            }
            let yb = &mut y[first * co..(first + avx2::ROWS) * co];
            // SAFETY: the CPU has AVX2 and FMA (tested above).
            #[allow(unsafe_code)]
            unsafe {
                avx2_rows::<M>(patch, red, wts, relu, yb)
            };
        }
        let dst = &mut patch[..red];
        for i in n..pixels {
            gather(x, win, ci, i / win.out_w, i % win.out_w, dst);
            let o = i * co;
            gemm_rows::<M, 1>(dst, red, &wts.w, &wts.bias, 0, relu, &mut y[o..o + co]);
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
            #[cfg(target_arch = "x86_64")]
            if avx512 {
                let at = super::avx512::InPlace::contiguous(red);
                // SAFETY: the CPU has AVX-512F (tested above).
                #[allow(unsafe_code)]
                unsafe {
                    super::avx512::conv_rows(dst, &at, 1, &wts.panels, &wts.bias, relu, y, o)
                };
                continue;
            }
            gemm_rows::<M, 1>(dst, red, &wts.w, &wts.bias, 0, relu, &mut y[o..o + co]);
        }
        if lo == hi {
            continue;
        }
        // Every kernel row is inside the input here, so the window's top row is too.
        let iy0 = oy * win.stride_h - win.pad_top;
        #[cfg(target_arch = "x86_64")]
        if avx512 {
            let at = super::avx512::InPlace {
                base: (iy0 * win.in_w + lo * win.stride_w - win.pad_left) * ci,
                step: win.stride_w * ci,
                k_h: win.k_h,
                row: win.in_w * ci,
                run: win.k_w * ci,
            };
            let y0 = (oy * win.out_w + lo) * co;
            // SAFETY: the CPU has AVX-512F (tested above).
            #[allow(unsafe_code)]
            unsafe {
                super::avx512::conv_rows(x, &at, hi - lo, &wts.panels, &wts.bias, relu, y, y0)
            };
            continue;
        }
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

/// Every output channel of `avx2::ROWS` pixels (`a` is `ROWS × red`, `y` is `ROWS × C_out`):
/// blocks of 16 channels by the explicit AVX2 kernel, the rest by [`gemm_rows`].
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
#[inline(always)]
unsafe fn avx2_rows<M: Madd>(
    a: &[f32],
    red: usize,
    wts: &Conv2dWeights,
    relu: bool,
    y: &mut [f32],
) {
    let mut ob = 0;
    while ob + 16 <= wts.c_out {
        // SAFETY: the caller's CPU has AVX2 and FMA.
        unsafe { avx2::gemm_x16(a, red, &wts.w, &wts.bias, ob, relu, y) };
        ob += 16;
    }
    gemm_rows::<M, { avx2::ROWS }>(a, red, &wts.w, &wts.bias, ob, relu, y);
}

/// The scratch [`conv2d`] needs for a `k_h × k_w` kernel over `c_in` channels: the windows of
/// the most pixels gathered for one micro-kernel call.
pub fn conv2d_scratch_len(k_h: usize, k_w: usize, c_in: usize) -> usize {
    #[cfg(target_arch = "x86_64")]
    let pixels = avx2::ROWS;
    #[cfg(not(target_arch = "x86_64"))]
    let pixels = 1;
    pixels * k_h * k_w * c_in
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
/// `R × red`, `w` is `red × C_out`, `y` is `R × C_out`; output channels `from ..` only. They go
/// in register blocks of 16, then 8, then 4, then one by one.
#[inline(always)]
fn gemm_rows<M: Madd, const R: usize>(
    a: &[f32],
    red: usize,
    w: &[f32],
    b: &[f32],
    from: usize,
    relu: bool,
    y: &mut [f32],
) {
    let co = b.len();
    let mut ob = from;
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

/// [`block`] for 16 output channels of [`avx2::ROWS`] pixels with AVX2 and FMA: twelve
/// accumulators in registers (the compiler's version of the generic block keeps eight and
/// reloads the input once per channel block), the same order of multiply-adds, so the same
/// values bit for bit.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod avx2 {
    use std::arch::x86_64::{
        __m256, _mm256_broadcast_ss, _mm256_fmadd_ps, _mm256_loadu_ps, _mm256_max_ps,
        _mm256_setzero_ps, _mm256_storeu_ps,
    };

    /// Pixels per call.
    pub(super) const ROWS: usize = 6;

    /// Output channels `ob .. ob + 16` of `ROWS` pixels: `a` is `ROWS × red`, `w` is
    /// `red × C_out`, `y` is `ROWS × C_out` with `C_out = b.len()`.
    ///
    /// # Panics
    /// If a read or write would leave `a`, `w`, `b` or `y`.
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn gemm_x16(
        a: &[f32],
        red: usize,
        w: &[f32],
        b: &[f32],
        ob: usize,
        relu: bool,
        y: &mut [f32],
    ) {
        let co = b.len();
        assert!(red > 0 && ob + 16 <= co);
        assert!(a.len() >= ROWS * red && w.len() >= (red - 1) * co + ob + 16);
        assert!(y.len() >= (ROWS - 1) * co + ob + 16);
        let (ap, wp, yp) = (a.as_ptr(), w.as_ptr(), y.as_mut_ptr());
        // The asserts above bound the highest index each load and store below touches: input
        // row ROWS − 1 at red − 1, weight row red − 1, output row ROWS − 1, channels below
        // ob + 16.
        // SAFETY: ob + 16 ≤ b.len() (asserted).
        let bias = unsafe {
            [
                _mm256_loadu_ps(b.as_ptr().add(ob)),
                _mm256_loadu_ps(b.as_ptr().add(ob + 8)),
            ]
        };
        let mut acc: [[__m256; 2]; ROWS] = [bias; ROWS];
        for r in 0..red {
            // SAFETY: as above.
            let wr = unsafe {
                let p = wp.add(r * co + ob);
                [_mm256_loadu_ps(p), _mm256_loadu_ps(p.add(8))]
            };
            for (p, row) in acc.iter_mut().enumerate() {
                // SAFETY: as above.
                let av = unsafe { _mm256_broadcast_ss(&*ap.add(p * red + r)) };
                row[0] = _mm256_fmadd_ps(av, wr[0], row[0]);
                row[1] = _mm256_fmadd_ps(av, wr[1], row[1]);
            }
        }
        if relu {
            let zero = _mm256_setzero_ps();
            for row in acc.iter_mut() {
                row[0] = _mm256_max_ps(row[0], zero);
                row[1] = _mm256_max_ps(row[1], zero);
            }
        }
        for (p, row) in acc.iter().enumerate() {
            // SAFETY: as above.
            unsafe {
                let o = yp.add(p * co + ob);
                _mm256_storeu_ps(o, row[0]);
                _mm256_storeu_ps(o.add(8), row[1]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::test_values;
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
            // The windowed kernel's gathered groups of pixels (with AVX2): the networks' 2 × 2
            // stride-2 reductions (a 2 × 2 and a 4 × 4 output: no whole group, and groups with a
            // remainder), a strided 3 × 3 first layer, channels past the last block of 16.
            (4, 4, 8, 64, 2, 2, Padding::Valid),
            (8, 8, 8, 32, 2, 2, Padding::Valid),
            (12, 10, 3, 16, 3, 2, Padding::Same),
            (6, 7, 5, 21, 3, 1, Padding::Same),
            // 1×1: whole groups of pixels and channel blocks of 16 for the vector kernel, with
            // and without remainders.
            (7, 9, 40, 48, 1, 1, Padding::Same),
            (2, 3, 16, 16, 1, 1, Padding::Same),
            (3, 5, 8, 37, 1, 1, Padding::Same),
        ] {
            let win = Window::new(h, w, [k, k], [s, s], pad);
            let x = test_values(h * w * ci, 1);
            let ohwi = test_values(co * k * k * ci, 2);
            let b = test_values(co, 3);
            let wts = Conv2dWeights::from_ohwi(&ohwi, co, k, k, ci, b.clone());
            let mut y = vec![0.0; win.out_h * win.out_w * co];
            let mut patch = vec![0.0; conv2d_scratch_len(k, k, ci)];
            conv2d::<crate::ops::Plain>(&x, &win, &wts, Activation::None, &mut patch, &mut y);
            let mut y2 = vec![0.0; y.len()];
            conv2d::<crate::ops::Fused>(&x, &win, &wts, Activation::None, &mut patch, &mut y2);
            for (a, b) in y.iter().zip(&y2) {
                assert!((a - b).abs() < 1e-5);
            }
            // The AVX-512 kernel (where the CPU has it) and the AVX2 and generic ones: the same
            // values bit for bit.
            #[cfg(target_arch = "x86_64")]
            {
                let mut y4 = vec![0.0; y.len()];
                crate::ops::avx512::without(|| {
                    conv2d::<crate::ops::Fused>(
                        &x,
                        &win,
                        &wts,
                        Activation::None,
                        &mut patch,
                        &mut y4,
                    )
                });
                for (a, b) in y4.iter().zip(&y2) {
                    assert_eq!(a.to_bits(), b.to_bits(), "{h}x{w}x{ci}->{co} k{k} s{s}");
                }
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
            conv2d::<crate::ops::Fused>(&x, &win, &wts, Activation::Relu, &mut patch, &mut y3);
            for (a, b) in y3.iter().zip(&y2) {
                assert_eq!(*a, b.max(0.0));
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
        let mut patch = vec![0.0; conv2d_scratch_len(1, 1, 1)];
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
