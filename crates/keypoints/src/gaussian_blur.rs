//! Separable Gaussian blur with OpenCV's kernel size and border rule, written so that the
//! loops vectorise (one tap over a whole row at a time).

use crate::GrayImage;

/// Kernel radius in standard deviations (OpenCV's `GaussianBlur` for float images:
/// `ksize = round(8σ + 1) | 1`).
const RADIUS_IN_SIGMAS: f64 = 4.0;

/// A normalised, symmetric 1-D Gaussian kernel.
#[derive(Clone, Debug, PartialEq)]
pub struct GaussianKernel {
    /// `taps[0]` the centre weight, `taps[i]` the weight at offsets ±i.
    taps: Vec<f32>,
}

impl GaussianKernel {
    /// The kernel of standard deviation `sigma` pixels, `2r + 1` taps with
    /// `2r + 1 = round(2 · 4σ + 1) | 1`, weights `exp(−i²/2σ²)` normalised to sum 1.
    pub fn new(sigma: f64) -> Self {
        let size = ((sigma * RADIUS_IN_SIGMAS * 2.0 + 1.0).round() as usize) | 1;
        let radius = size / 2;
        let weights: Vec<f64> = (0..=radius)
            .map(|i| (-((i * i) as f64) / (2.0 * sigma * sigma)).exp())
            .collect();
        let sum = weights[0] + 2.0 * weights[1..].iter().sum::<f64>();
        GaussianKernel {
            taps: weights.iter().map(|w| (w / sum) as f32).collect(),
        }
    }

    /// Taps on either side of the centre.
    pub fn radius(&self) -> usize {
        self.taps.len() - 1
    }
}

/// OpenCV's `BORDER_REFLECT_101` (`gfedcb|abcdefgh|gfedcba`) for an index `i` of a line of `n`.
#[inline]
fn reflect101(i: isize, n: usize) -> usize {
    if i >= 0 && (i as usize) < n {
        return i as usize;
    }
    if n == 1 {
        return 0;
    }
    let period = 2 * (n as isize - 1);
    let mut j = i.rem_euclid(period);
    if j >= n as isize {
        j = period - j;
    }
    j as usize
}

/// Reusable buffers of [`gaussian_blur`].
#[derive(Clone, Debug, Default)]
pub struct BlurScratch {
    padded: Vec<f32>,
    ring: Vec<f32>,
    pairs: Vec<(usize, usize)>,
}

/// `dst = G_σ * src` (separable; borders by reflection without repeating the edge pixel, as
/// OpenCV's default). `dst` is resized to `src`'s size.
pub fn gaussian_blur(
    src: &GrayImage,
    dst: &mut GrayImage,
    kernel: &GaussianKernel,
    scratch: &mut BlurScratch,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: `gaussian_blur_avx2` is compiled for AVX2, which the run-time check just
        // above found on this CPU; its body is the safe, bounds-checked `blur`. (Eight lanes
        // instead of SSE2's four: docs/performance.md has the blur's time with and without.)
        unsafe { gaussian_blur_avx2(src, dst, kernel, scratch) };
        return;
    }
    blur(src, dst, kernel, scratch);
}

/// [`blur`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn gaussian_blur_avx2(
    src: &GrayImage,
    dst: &mut GrayImage,
    kernel: &GaussianKernel,
    scratch: &mut BlurScratch,
) {
    blur(src, dst, kernel, scratch);
}

/// The separable blur, streamed: rows are filtered horizontally into a ring of `2r + 1` rows
/// (which stays in cache) just before the vertical pass needs them, instead of through a
/// whole intermediate image. Every row an output row reads, reflections included, lies
/// within `r` rows of it, so the ring always holds them. Inlined into each instruction-set
/// variant.
#[inline(always)]
fn blur(src: &GrayImage, dst: &mut GrayImage, kernel: &GaussianKernel, scratch: &mut BlurScratch) {
    let (w, h) = (src.width(), src.height());
    let r = kernel.radius();
    let taps = &kernel.taps;
    let slots = 2 * r + 1;
    scratch.ring.resize(slots * w, 0.0);
    dst.resize(w, h);
    let mut next = 0;
    let centred: Vec<(usize, usize)> = (1..=r).map(|i| (r - i, r + i)).collect();
    let pairs = &mut scratch.pairs;
    for y in 0..h {
        while next <= (y + r).min(h - 1) {
            let slot = next % slots;
            horizontal(
                src.row(next),
                taps,
                &centred,
                &mut scratch.padded,
                &mut scratch.ring[slot * w..(slot + 1) * w],
            );
            next += 1;
        }
        let start = |k: usize| (k % slots) * w;
        pairs.clear();
        pairs.extend((1..=r).map(|i| {
            (
                start(reflect101(y as isize - i as isize, h)),
                start(reflect101((y + i) as isize, h)),
            )
        }));
        let out = &mut dst.data_mut()[y * w..(y + 1) * w];
        combine(&scratch.ring, start(y), pairs, taps, out);
    }
}

/// The horizontal pass over one row: the interior straight from the row, the `r` pixels at
/// each end from a short reflected copy. `pairs` are the offsets `(r − i, r + i)`.
#[inline(always)]
fn horizontal(
    row: &[f32],
    taps: &[f32],
    pairs: &[(usize, usize)],
    padded: &mut Vec<f32>,
    out: &mut [f32],
) {
    let (w, r) = (row.len(), taps.len() - 1);
    if w <= 2 * r {
        padded.clear();
        padded.extend((0..w + 2 * r).map(|i| row[reflect101(i as isize - r as isize, w)]));
        combine(padded, r, pairs, taps, out);
        return;
    }
    combine(row, r, pairs, taps, &mut out[r..w - r]);
    // The ends: 3r samples around each (reflected where they leave the row), r outputs.
    padded.clear();
    padded.extend((1..=r).rev().map(|k| row[k]));
    padded.extend_from_slice(&row[..2 * r]);
    combine(padded, r, pairs, taps, &mut out[..r]);
    padded.clear();
    padded.extend_from_slice(&row[w - 2 * r..]);
    padded.extend((1..=r).map(|k| row[w - 1 - k]));
    combine(padded, r, pairs, taps, &mut out[w - r..]);
}

/// Pixels per block of [`combine`]: eight AVX registers of accumulators, enough independent
/// sums to hide the adds' latency (16 pixels: 12.5 ms for a 2560 × 1440 blur; 64: 6–9 ms).
const BLOCK: usize = 64;

/// Pixels per block on rows shorter than [`BLOCK`] and for the remainder of longer ones.
const SMALL_BLOCK: usize = 8;

/// `out[x] = taps[0] · buf[centre + x] + Σ_i taps[i] · (buf[a_i + x] + buf[b_i + x])` for the
/// offset pairs `(a_i, b_i)` — one blur pass over a row, horizontal (offsets into a row) or
/// vertical (offsets of rows in the ring). Blocks of pixels keep their sums in registers
/// across all taps, so each input is loaded once per tap and each output stored once; the
/// last block of a row overlaps the one before instead of falling back to scalar code.
#[inline(always)]
fn combine(buf: &[f32], centre: usize, pairs: &[(usize, usize)], taps: &[f32], out: &mut [f32]) {
    let n = out.len();
    if n >= BLOCK {
        let mut x = 0;
        while x + BLOCK <= n {
            combine_block::<BLOCK>(buf, centre, pairs, taps, out, x);
            x += BLOCK;
        }
        if x < n {
            combine_block::<BLOCK>(buf, centre, pairs, taps, out, n - BLOCK);
        }
    } else if n >= SMALL_BLOCK {
        let mut x = 0;
        while x + SMALL_BLOCK <= n {
            combine_block::<SMALL_BLOCK>(buf, centre, pairs, taps, out, x);
            x += SMALL_BLOCK;
        }
        if x < n {
            combine_block::<SMALL_BLOCK>(buf, centre, pairs, taps, out, n - SMALL_BLOCK);
        }
    } else {
        for x in 0..n {
            let mut s = taps[0] * buf[centre + x];
            for (&k, &(a, b)) in taps[1..].iter().zip(pairs) {
                s += k * (buf[a + x] + buf[b + x]);
            }
            out[x] = s;
        }
    }
}

/// [`combine`] for the `B` pixels from `x`.
#[inline(always)]
fn combine_block<const B: usize>(
    buf: &[f32],
    centre: usize,
    pairs: &[(usize, usize)],
    taps: &[f32],
    out: &mut [f32],
    x: usize,
) {
    let mut acc = [0.0f32; B];
    for (s, &v) in acc.iter_mut().zip(&buf[centre + x..centre + x + B]) {
        *s = taps[0] * v;
    }
    for (&k, &(a, b)) in taps[1..].iter().zip(pairs) {
        let (a, b) = (&buf[a + x..a + x + B], &buf[b + x..b + x + B]);
        for ((s, &u), &v) in acc.iter_mut().zip(a).zip(b) {
            *s += k * (u + v);
        }
    }
    out[x..x + B].copy_from_slice(&acc);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_matches_opencv_size_and_sums_to_one() {
        // getGaussianKernel(ksize = round(8σ+1)|1, σ): σ = 1.6 → 15 taps (radius 7).
        let k = GaussianKernel::new(1.6);
        assert_eq!(k.radius(), 7);
        let sum: f32 = k.taps[0] + 2.0 * k.taps[1..].iter().sum::<f32>();
        assert!((sum - 1.0).abs() < 1e-6);
        assert!(k.taps.windows(2).all(|w| w[0] > w[1]));
    }

    #[test]
    fn reflect101_mirrors_without_repeating_the_edge() {
        let n = 5;
        let got: Vec<usize> = (-3..8).map(|i| reflect101(i, n)).collect();
        assert_eq!(got, vec![3, 2, 1, 0, 1, 2, 3, 4, 3, 2, 1]);
        assert_eq!(reflect101(-4, 1), 0);
    }

    /// The 2-D convolution written out, with the same border rule.
    fn naive(src: &GrayImage, kernel: &GaussianKernel) -> Vec<f32> {
        let (w, h, r) = (src.width(), src.height(), kernel.radius() as isize);
        let tap = |i: isize| kernel.taps[i.unsigned_abs()];
        let mut out = vec![0.0; w * h];
        for y in 0..h as isize {
            for x in 0..w as isize {
                let mut s = 0.0;
                for dy in -r..=r {
                    for dx in -r..=r {
                        let v = src.at(reflect101(x + dx, w), reflect101(y + dy, h));
                        s += tap(dx) * tap(dy) * v;
                    }
                }
                out[y as usize * w + x as usize] = s;
            }
        }
        out
    }

    #[test]
    fn blur_equals_the_written_out_convolution_at_every_width() {
        let kernel = GaussianKernel::new(1.6); // radius 7
        let mut scratch = BlurScratch::default();
        let mut out = GrayImage::default();
        // Narrower than the kernel, between one and two blocks, and the block edges.
        for (w, h) in [(5, 4), (13, 9), (16, 17), (71, 12), (64, 3), (130, 20)] {
            let data = (0..w * h)
                .map(|i| ((i * 37 + i / w * 11) % 255) as f32)
                .collect();
            let src = GrayImage::from_vec(w, h, data).unwrap();
            gaussian_blur(&src, &mut out, &kernel, &mut scratch);
            for (k, (&got, want)) in out.data().iter().zip(naive(&src, &kernel)).enumerate() {
                assert!((got - want).abs() < 1e-3, "{w}×{h} at {k}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn blur_keeps_constants_and_mass_and_spreads_an_impulse_as_a_gaussian() {
        let constant = GrayImage::from_vec(9, 7, vec![3.5; 63]).unwrap();
        let mut out = GrayImage::default();
        let mut scratch = BlurScratch::default();
        let kernel = GaussianKernel::new(1.2);
        gaussian_blur(&constant, &mut out, &kernel, &mut scratch);
        assert!(out.data().iter().all(|v| (v - 3.5).abs() < 1e-5));

        let (w, h) = (41, 41);
        let mut impulse = vec![0.0; w * h];
        impulse[20 * w + 20] = 1.0;
        let impulse = GrayImage::from_vec(w, h, impulse).unwrap();
        let sigma = 2.0;
        gaussian_blur(
            &impulse,
            &mut out,
            &GaussianKernel::new(sigma),
            &mut scratch,
        );
        let total: f32 = out.data().iter().sum();
        assert!((total - 1.0).abs() < 1e-5, "mass {total}");
        // Second moment of the response = σ² along each axis.
        let var_x: f32 = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| out.at(x, y) * (x as f32 - 20.0).powi(2))
            .sum();
        assert!((var_x - 4.0).abs() < 0.01, "variance {var_x}");
        assert!((out.at(21, 20) - out.at(20, 21)).abs() < 1e-7);
    }
}
