//! The convolutions' hot loops with AVX-512 (16 lanes, 32 vector registers), chosen at run time
//! where the CPU has it and the network runs with fused multiply-adds (see `Madd::FUSED`):
//!
//! - [`conv_rows`]: a GEMM register block of 12 pixels × 32 output channels (24 accumulators)
//!   whose left-hand rows are read in place from the input, so one kernel serves the 1×1
//!   convolutions, the interior windows of the k×k ones and their border windows (gathered);
//! - [`depthwise_row3`]: the depthwise 3×3 row sweep, 16 channels and 8 output columns at a
//!   time, and [`depthwise_pixel`] for the pixels whose window the input clips.
//!
//! Each keeps the generic kernels' order of multiply-adds per output value (the bias, then the
//! taps in the weights' order), so the outputs are the same values bit for bit as the AVX2 and
//! generic code with fused multiply-adds. Channel counts that are not multiples of 16 are
//! handled with masked loads and stores, which touch no memory in their masked-off lanes.
#![allow(unsafe_code)]

use super::row_sweep::Row3;
use std::arch::x86_64::{
    __m512, __mmask16, _mm512_fmadd_ps, _mm512_loadu_ps, _mm512_mask_storeu_ps,
    _mm512_maskz_loadu_ps, _mm512_max_ps, _mm512_set1_ps, _mm512_setzero_ps,
};

/// The environment variable that switches this module's kernels off (any value), so that a
/// machine with AVX-512 can measure what one with AVX2 only would run.
const NO_AVX512_VARIABLE: &str = "VISAGE_NO_AVX512";

/// Whether this CPU runs the kernels of this module: it has AVX-512F and
/// [`NO_AVX512_VARIABLE`] is not set (read once per process).
pub(super) fn available() -> bool {
    #[cfg(test)]
    if AVX2_ONLY.with(std::cell::Cell::get) {
        return false;
    }
    static AVAILABLE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *AVAILABLE.get_or_init(|| {
        std::arch::is_x86_feature_detected!("avx512f")
            && std::env::var_os(NO_AVX512_VARIABLE).is_none()
    })
}

#[cfg(test)]
thread_local! {
    /// Set by a test on its own thread to run the AVX2 and generic kernels on a CPU with
    /// AVX-512, and compare them with these.
    pub(super) static AVX2_ONLY: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// `f()` with this module's kernels off on this thread (the AVX2 ones run instead).
#[cfg(test)]
pub(super) fn without<T>(f: impl FnOnce() -> T) -> T {
    AVX2_ONLY.with(|c| c.set(true));
    let out = f();
    AVX2_ONLY.with(|c| c.set(false));
    out
}

/// The mask of the first `n.min(16)` lanes.
#[inline(always)]
fn lanes(n: usize) -> __mmask16 {
    if n >= 16 {
        0xffff
    } else {
        (1u16 << n) - 1
    }
}

/// Where the left-hand rows of a GEMM lie in the input: pixel `p`'s reduction values are the
/// `k_h` runs `x[base + p·step + ky·row ..][..run]`, `ky < k_h`, one after another (for a 1×1
/// convolution `k_h = 1` and `run = step = C_in`; for a k×k window inside the input, `row` is
/// an input row's length and `run = k_w·C_in`).
pub(super) struct InPlace {
    pub base: usize,
    pub step: usize,
    pub k_h: usize,
    pub row: usize,
    pub run: usize,
}

impl InPlace {
    /// Rows of `len` values one after another from the start (a 1×1 convolution's input, or
    /// gathered windows).
    pub(super) fn contiguous(len: usize) -> InPlace {
        InPlace {
            base: 0,
            step: len,
            k_h: 1,
            row: 0,
            run: len,
        }
    }
}

/// Pixels per register block.
const ROWS: usize = 12;

/// Output channels per weight panel.
const PANEL: usize = 32;

/// The width of the panel that starts at output channel `ob` of `co`: 32, or 16 for a last one
/// of at most 16 channels (the kernel's blocks of two and one vectors).
fn panel_width(co: usize, ob: usize) -> usize {
    if co - ob > 16 {
        PANEL
    } else {
        16
    }
}

/// The weights `w` (`red × C_out`, output channels contiguous) in the order [`conv_rows`]
/// streams them: panels of [`PANEL`] output channels (16 for a last one of at most 16), each
/// `red × width` contiguous and zero-padded past `C_out`, so that a register block reads its
/// weights as one sequential run.
pub(super) fn pack(w: &[f32], red: usize, co: usize) -> Vec<f32> {
    assert_eq!(w.len(), red * co, "pack sizes");
    let mut out = Vec::with_capacity(packed_len(red, co));
    let mut ob = 0;
    while ob < co {
        let width = panel_width(co, ob);
        let n = width.min(co - ob);
        for r in 0..red {
            out.extend_from_slice(&w[r * co + ob..r * co + ob + n]);
            out.extend(std::iter::repeat_n(0.0, width - n));
        }
        ob += width;
    }
    out
}

/// The length of [`pack`]'s output.
fn packed_len(red: usize, co: usize) -> usize {
    let tail = match co % PANEL {
        0 => 0,
        1..=16 => 16,
        _ => PANEL,
    };
    red * (co / PANEL * PANEL + tail)
}

/// `y[y0 + p·C_out + o] = b[o] + Σ_r a[p, r] · w[r·C_out + o]` (then `max(·, 0)` if `relu`)
/// for the `n` pixels `p` whose rows `a[p, ·]` [`InPlace`] describes; `C_out = b.len()`, the
/// weights `w` as [`pack`] lays them out.
///
/// # Panics
/// If a read or write would leave `x`, `w`, `b` or `y`.
#[allow(clippy::too_many_arguments)]
#[target_feature(enable = "avx512f")]
pub(super) fn conv_rows(
    x: &[f32],
    at: &InPlace,
    n: usize,
    w: &[f32],
    b: &[f32],
    relu: bool,
    y: &mut [f32],
    y0: usize,
) {
    let co = b.len();
    let red = at.k_h * at.run;
    if n == 0 || co == 0 {
        return;
    }
    assert!(
        red > 0 && w.len() == packed_len(red, co),
        "conv_rows weights"
    );
    assert!(
        at.base + (n - 1) * at.step + (at.k_h - 1) * at.row + at.run <= x.len(),
        "conv_rows input"
    );
    assert!(y0 + n * co <= y.len(), "conv_rows output");
    // The asserts bound every index below: pixel rows below n, runs inside x, weight panels
    // inside w, output channels below co (the masks keep the loads and stores of a partial
    // block of channels inside it).
    let (xp, wp, yp) = (x.as_ptr(), w.as_ptr(), y.as_mut_ptr());
    let mut p0 = 0;
    while p0 < n {
        let left = n - p0;
        // SAFETY: pixels p0 .. p0 + R with R ≤ left (asserted bounds above).
        unsafe {
            if left >= ROWS {
                pixels::<ROWS>(xp, at, p0, wp, b, relu, yp, y0);
                p0 += ROWS;
            } else if left >= 4 {
                pixels::<4>(xp, at, p0, wp, b, relu, yp, y0);
                p0 += 4;
            } else {
                pixels::<1>(xp, at, p0, wp, b, relu, yp, y0);
                p0 += 1;
            }
        }
    }
}

/// Every output channel of pixels `p0 .. p0 + R` of [`conv_rows`]: blocks of 32 channels, then
/// one of up to 16.
///
/// # Safety
/// The CPU has AVX-512F; pixels `p0 .. p0 + R` lie within `conv_rows`' checked bounds.
#[allow(clippy::too_many_arguments)]
#[inline]
#[target_feature(enable = "avx512f")]
unsafe fn pixels<const R: usize>(
    xp: *const f32,
    at: &InPlace,
    p0: usize,
    wp: *const f32,
    b: &[f32],
    relu: bool,
    yp: *mut f32,
    y0: usize,
) {
    let co = b.len();
    let red = at.k_h * at.run;
    let mut ob = 0;
    while ob < co {
        // Panel `ob / PANEL` starts after the full panels before it.
        let panel = wp.wrapping_add(ob * red);
        // SAFETY: as the caller's; channels ob .. ob + 16·NV masked to below co, the panel's
        // red × 16·NV weights inside w (conv_rows checked its packed length).
        unsafe {
            if panel_width(co, ob) == PANEL {
                let m = [0xffff, lanes(co - ob - 16)];
                block::<R, 2>(xp, at, p0, panel, b, ob, m, relu, yp, y0);
            } else {
                block::<R, 1>(xp, at, p0, panel, b, ob, [lanes(co - ob)], relu, yp, y0);
            }
        }
        ob += PANEL;
    }
}

/// The `R × 16·NV` register block: pixels `p0 .. p0 + R`, channels `ob ..` under `masks`,
/// their weights the panel at `panel` (`red × 16·NV`).
///
/// # Safety
/// As [`pixels`]; the masks' lanes lie below `C_out`; the panel lies inside the weights.
#[allow(clippy::too_many_arguments)]
#[inline]
#[target_feature(enable = "avx512f")]
unsafe fn block<const R: usize, const NV: usize>(
    xp: *const f32,
    at: &InPlace,
    p0: usize,
    panel: *const f32,
    b: &[f32],
    ob: usize,
    masks: [__mmask16; NV],
    relu: bool,
    yp: *mut f32,
    y0: usize,
) {
    let co = b.len();
    // Every load and store below stays within the bounds the caller guarantees: the bias and
    // outputs at channels the masks keep below C_out, the panel's rows below the reduction
    // length, input runs of pixels p0 .. p0 + R.
    // SAFETY: as above.
    let bias: [__m512; NV] = std::array::from_fn(|v| unsafe {
        _mm512_maskz_loadu_ps(masks[v], b.as_ptr().add(ob + 16 * v))
    });
    let mut acc = [bias; R];
    let mut wr_row = panel;
    for ky in 0..at.k_h {
        let a = xp.wrapping_add(at.base + p0 * at.step + ky * at.row);
        for t in 0..at.run {
            // SAFETY: as above (the panel is zero-padded to whole vectors).
            let wr: [__m512; NV] =
                std::array::from_fn(|v| unsafe { _mm512_loadu_ps(wr_row.add(16 * v)) });
            for (p, row) in acc.iter_mut().enumerate() {
                // SAFETY: as above.
                let av = _mm512_set1_ps(unsafe { *a.add(p * at.step + t) });
                for v in 0..NV {
                    row[v] = _mm512_fmadd_ps(av, wr[v], row[v]);
                }
            }
            wr_row = wr_row.wrapping_add(16 * NV);
        }
    }
    if relu {
        let zero = _mm512_setzero_ps();
        for row in acc.iter_mut() {
            for v in row.iter_mut() {
                *v = _mm512_max_ps(*v, zero);
            }
        }
    }
    for (p, row) in acc.iter().enumerate() {
        for v in 0..NV {
            // SAFETY: as above.
            unsafe {
                _mm512_mask_storeu_ps(yp.add(y0 + (p0 + p) * co + ob + 16 * v), masks[v], row[v])
            };
        }
    }
}

/// Output columns per register block of [`depthwise_row3`].
const COLS: usize = 8;

/// Every channel of `at.n` output columns of a depthwise 3×3 convolution whose windows lie
/// inside the input: `y = b + Σ_{ky, kx} w[ky, kx] · x[tap]`, taps in the weights' order.
///
/// # Panics
/// If a read or write would leave `x`, `w`, `b` or `y`.
#[target_feature(enable = "avx512f")]
pub(super) fn depthwise_row3(x: &[f32], w: &[f32], b: &[f32], at: &Row3, y: &mut [f32]) {
    let c = b.len();
    if at.n == 0 || c == 0 {
        return;
    }
    let last = at.n - 1;
    assert!(
        at.x0 + last * at.step + 2 * at.row + 3 * c <= x.len(),
        "depthwise_row3 input"
    );
    assert!(at.y0 + at.n * c <= y.len(), "depthwise_row3 output");
    assert!(w.len() >= 9 * c, "depthwise_row3 weights");
    let (xp, yp) = (x.as_ptr(), y.as_mut_ptr());
    let mut cb = 0;
    while cb < c {
        let m = lanes(c - cb);
        // The asserts bound every index: tap (2, 2) of the last column, the last column's
        // output, weight tap 8, all at channels below c (masked).
        // SAFETY: as above.
        let (wk, bias): ([__m512; 9], __m512) = unsafe {
            (
                std::array::from_fn(|t| _mm512_maskz_loadu_ps(m, w.as_ptr().add(t * c + cb))),
                _mm512_maskz_loadu_ps(m, b.as_ptr().add(cb)),
            )
        };
        let mut p = 0;
        // SAFETY: columns p .. p + N below at.n, channels masked below c.
        unsafe {
            if at.step == c {
                while p + COLS <= at.n {
                    columns_stride1(xp, &wk, bias, m, at, c, cb, p, yp);
                    p += COLS;
                }
            }
            while p + COLS <= at.n {
                columns::<COLS>(xp, &wk, bias, m, at, c, cb, p, yp);
                p += COLS;
            }
            while p < at.n {
                columns::<1>(xp, &wk, bias, m, at, c, cb, p, yp);
                p += 1;
            }
        }
        cb += 16;
    }
}

/// [`columns`] for `COLS` columns at stride 1, where neighbouring columns share taps: each
/// input row's `COLS + 2` pixels are loaded once and serve all three kernel columns (30 loads
/// for 72 multiply-adds, not 72); the multiply-adds keep their order.
///
/// # Safety
/// As [`columns`] with `N = COLS`, and `at.step == c`.
#[allow(clippy::too_many_arguments)]
#[inline]
#[target_feature(enable = "avx512f")]
unsafe fn columns_stride1(
    xp: *const f32,
    wk: &[__m512; 9],
    bias: __m512,
    m: __mmask16,
    at: &Row3,
    c: usize,
    cb: usize,
    p: usize,
    yp: *mut f32,
) {
    let xb = at.x0 + p * c + cb;
    let mut acc = [bias; COLS];
    for ky in 0..3 {
        let xi = xb + ky * at.row;
        // Pixels p .. p + COLS + 2 of the row: column q's tap kx is pixel q + kx.
        // SAFETY: as the caller's (the last is tap (ky, 2) of column p + COLS − 1).
        let v: [__m512; COLS + 2] =
            std::array::from_fn(|i| unsafe { _mm512_maskz_loadu_ps(m, xp.add(xi + i * c)) });
        for kx in 0..3 {
            for (q, a) in acc.iter_mut().enumerate() {
                *a = _mm512_fmadd_ps(v[q + kx], wk[ky * 3 + kx], *a);
            }
        }
    }
    for (q, a) in acc.iter().enumerate() {
        // SAFETY: as the caller's.
        unsafe { _mm512_mask_storeu_ps(yp.add(at.y0 + (p + q) * c + cb), m, *a) };
    }
}

/// The taps of one depthwise output pixel whose window the input clips: rows `ky.0 .. ky.1`
/// and columns `kx.0 .. kx.1` of a kernel `k_w` wide; tap `(ky.0, kx.0)` at `x0`, input rows
/// `row` values apart; the output at `y0`.
pub(super) struct Taps {
    pub x0: usize,
    pub row: usize,
    pub ky: (usize, usize),
    pub kx: (usize, usize),
    pub k_w: usize,
    pub y0: usize,
}

/// Every channel of one depthwise output pixel, any window: `y = b + Σ w[ky, kx] · x[tap]` over
/// the valid taps, row by row (the generic kernel's order).
///
/// # Panics
/// If a read or write would leave `x`, `w`, `b` or `y`.
#[target_feature(enable = "avx512f")]
pub(super) fn depthwise_pixel(x: &[f32], w: &[f32], b: &[f32], at: &Taps, y: &mut [f32]) {
    let c = b.len();
    let ((ky0, ky1), (kx0, kx1)) = (at.ky, at.kx);
    assert!(at.y0 + c <= y.len(), "depthwise_pixel output");
    if ky1 > ky0 && kx1 > kx0 {
        assert!(kx1 <= at.k_w, "depthwise_pixel window");
        assert!(
            at.x0 + (ky1 - ky0 - 1) * at.row + (kx1 - kx0) * c <= x.len(),
            "depthwise_pixel input"
        );
        assert!(
            (ky1 - 1) * at.k_w * c + kx1 * c <= w.len(),
            "depthwise_pixel weights"
        );
    }
    let (xp, wp, yp) = (x.as_ptr(), w.as_ptr(), y.as_mut_ptr());
    let mut cb = 0;
    while cb < c {
        let m = lanes(c - cb);
        // The asserts bound every index: the last valid tap's channels, its weights and the
        // output, at channels the mask keeps below c.
        // SAFETY: as above.
        let mut acc = unsafe { _mm512_maskz_loadu_ps(m, b.as_ptr().add(cb)) };
        for ky in ky0..ky1 {
            for kx in kx0..kx1 {
                let xi = at.x0 + (ky - ky0) * at.row + (kx - kx0) * c + cb;
                let wi = (ky * at.k_w + kx) * c + cb;
                // SAFETY: as above.
                let (xv, wv) = unsafe {
                    (
                        _mm512_maskz_loadu_ps(m, xp.add(xi)),
                        _mm512_maskz_loadu_ps(m, wp.add(wi)),
                    )
                };
                acc = _mm512_fmadd_ps(xv, wv, acc);
            }
        }
        // SAFETY: as above.
        unsafe { _mm512_mask_storeu_ps(yp.add(at.y0 + cb), m, acc) };
        cb += 16;
    }
}

/// Channels `cb ..` (mask `m`) of output columns `p .. p + N` of [`depthwise_row3`]: N
/// independent chains of nine multiply-adds.
///
/// # Safety
/// The CPU has AVX-512F; the columns and channels lie within `depthwise_row3`'s checked bounds.
#[allow(clippy::too_many_arguments)]
#[inline]
#[target_feature(enable = "avx512f")]
unsafe fn columns<const N: usize>(
    xp: *const f32,
    wk: &[__m512; 9],
    bias: __m512,
    m: __mmask16,
    at: &Row3,
    c: usize,
    cb: usize,
    p: usize,
    yp: *mut f32,
) {
    let xb = at.x0 + p * at.step + cb;
    let mut acc = [bias; N];
    for ky in 0..3 {
        for kx in 0..3 {
            let xi = xb + ky * at.row + kx * c;
            for (q, a) in acc.iter_mut().enumerate() {
                // SAFETY: as the caller's.
                let xv = unsafe { _mm512_maskz_loadu_ps(m, xp.add(xi + q * at.step)) };
                *a = _mm512_fmadd_ps(xv, wk[ky * 3 + kx], *a);
            }
        }
    }
    for (q, a) in acc.iter().enumerate() {
        // SAFETY: as the caller's.
        unsafe { _mm512_mask_storeu_ps(yp.add(at.y0 + (p + q) * c + cb), m, *a) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::test_values;

    /// The kernels give the values of scalar fused multiply-adds in the generic kernels' order,
    /// bit for bit, for channel counts with and without a partial block of 16 and pixel counts
    /// with whole register blocks and remainders.
    #[test]
    fn same_values_as_scalar_fused_multiply_adds() {
        if !available() {
            eprintln!("skipped: this CPU has no AVX-512F");
            return;
        }
        for &(n, k_h, run, step, row, co) in &[
            (29, 1, 40, 40, 0, 48),
            (13, 1, 16, 16, 0, 16),
            (7, 3, 9, 6, 30, 37),
            (25, 2, 8, 8, 40, 20),
            (3, 1, 5, 5, 0, 3),
        ] {
            let at = InPlace {
                base: 2,
                step,
                k_h,
                row,
                run,
            };
            let red = k_h * run;
            let x = test_values(2 + (n - 1) * step + (k_h - 1) * row + run, 1);
            let w = test_values(red * co, 2);
            let b = test_values(co, 3);
            let packed = pack(&w, red, co);
            let mut y = vec![7.0; 5 + n * co];
            for relu in [false, true] {
                // SAFETY: the CPU has AVX-512F (tested above).
                unsafe { conv_rows(&x, &at, n, &packed, &b, relu, &mut y, 5) };
                for p in 0..n {
                    for o in 0..co {
                        let mut acc = b[o];
                        for ky in 0..k_h {
                            for t in 0..run {
                                let a = x[at.base + p * step + ky * row + t];
                                acc = a.mul_add(w[(ky * run + t) * co + o], acc);
                            }
                        }
                        let want = if relu { acc.max(0.0) } else { acc };
                        assert_eq!(y[5 + p * co + o].to_bits(), want.to_bits());
                    }
                }
                assert_eq!(y[..5], [7.0; 5]);
            }
        }
        for &(n, c, stride) in &[(19, 16, 1), (9, 21, 2), (4, 48, 1), (1, 5, 1)] {
            let (row, step) = ((n * stride + 2) * c, stride * c);
            let at = Row3 {
                row,
                step,
                x0: 3,
                y0: 1,
                n,
            };
            let x = test_values(3 + (n - 1) * step + 2 * row + 3 * c, 4);
            let w = test_values(9 * c, 5);
            let b = test_values(c, 6);
            let mut y = vec![0.0; 1 + n * c];
            // SAFETY: the CPU has AVX-512F (tested above).
            unsafe { depthwise_row3(&x, &w, &b, &at, &mut y) };
            for p in 0..n {
                for ch in 0..c {
                    let mut acc = b[ch];
                    for ky in 0..3 {
                        for kx in 0..3 {
                            let xv = x[3 + p * step + ky * row + kx * c + ch];
                            acc = xv.mul_add(w[(ky * 3 + kx) * c + ch], acc);
                        }
                    }
                    assert_eq!(y[1 + p * c + ch].to_bits(), acc.to_bits());
                }
            }
        }
        // A clipped 5×5 window: rows 1..5 and columns 0..3 of the kernel.
        let (c, k_w, row) = (21, 5, 40 * 21);
        let at = Taps {
            x0: 4,
            row,
            ky: (1, 5),
            kx: (0, 3),
            k_w,
            y0: 2,
        };
        let x = test_values(4 + 3 * row + 3 * c, 7);
        let w = test_values(25 * c, 8);
        let b = test_values(c, 9);
        let mut y = vec![0.0; 2 + c];
        // SAFETY: the CPU has AVX-512F (tested above).
        unsafe { depthwise_pixel(&x, &w, &b, &at, &mut y) };
        for ch in 0..c {
            let mut acc = b[ch];
            for ky in 1..5 {
                for kx in 0..3 {
                    let xv = x[4 + (ky - 1) * row + kx * c + ch];
                    acc = xv.mul_add(w[(ky * k_w + kx) * c + ch], acc);
                }
            }
            assert_eq!(y[2 + ch].to_bits(), acc.to_bits());
        }
    }
}
