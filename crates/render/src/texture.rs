//! Texture images and bilinear sampling: Eq. (6.3).

use std::path::Path;

use crate::color::srgb_to_linear_u8;
use crate::prefetch::prefetch;
use crate::shading::LANES;
use crate::RenderError;

/// What happens to texture coordinates outside `[0, 1]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// Use the nearest border texel (what projective texturing wants at the frame border).
    #[default]
    Clamp,
    /// Tile the texture (`u` and `u + 1` sample the same texel).
    Repeat,
}

/// An RGBA texture `Υ: [0, 1]² → [0, 1]⁴`, linear (not sRGB) values, `width × height` texels,
/// row-major with row 0 at the **top** of the image.
///
/// Texels are stored as 16-bit linear values (quantisation 1/65535, far below what an 8-bit
/// sRGB source carries) to halve the memory traffic of sampling large textures.
///
/// Texture coordinates follow OBJ/OpenGL: `u` to the right, `v` **up**, so `v = 0` is the bottom
/// row; the centre of texel `(i, j)` (column `i`, row `j` from the top) sits at
/// `((i + ½)/W, 1 − (j + ½)/H)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    width: u32,
    height: u32,
    texels: Vec<[u16; 4]>,
}

/// Scale of the 16-bit texel storage.
const TEXEL_MAX: f32 = u16::MAX as f32;

#[inline]
fn quantize(c: f32) -> u16 {
    (c.clamp(0.0, 1.0) * TEXEL_MAX + 0.5) as u16
}

impl Texture {
    /// A texture from linear RGBA texels (`width · height` of them, row 0 at the top).
    ///
    /// # Errors
    /// A zero size, a texel count that does not match, or a value outside `[0, 1]` (NaN included).
    pub fn new(width: u32, height: u32, texels: Vec<[f32; 4]>) -> Result<Texture, RenderError> {
        if width == 0 || height == 0 || texels.len() != width as usize * height as usize {
            return Err(RenderError::Parameter {
                field: "texture texel count",
                value: texels.len() as f64,
                reason: "must equal width · height > 0",
            });
        }
        if let Some(&bad) = texels.iter().flatten().find(|c| !(0.0..=1.0).contains(*c)) {
            return Err(RenderError::Parameter {
                field: "texel value",
                value: bad as f64,
                reason: "texture values must lie in [0, 1]",
            });
        }
        Ok(Texture {
            width,
            height,
            texels: texels.into_iter().map(|t| t.map(quantize)).collect(),
        })
    }

    /// Loads a PNG or JPEG image; its 8-bit values are taken as sRGB and converted to linear.
    /// Errors name the file.
    pub fn load(path: &Path) -> Result<Texture, RenderError> {
        let img = image::open(path).map_err(|e| RenderError::File {
            path: path.to_owned(),
            reason: format!("cannot read texture image: {e}"),
        })?;
        Ok(Texture::from_rgba8(&img.to_rgba8()))
    }

    /// A texture from an 8-bit sRGB image (alpha kept linear).
    pub fn from_rgba8(img: &image::RgbaImage) -> Texture {
        // One conversion per byte value, not per texel (a 1024² texture took 0.6 s).
        let linear: [u16; 256] = std::array::from_fn(|c| quantize(srgb_to_linear_u8(c as u8)));
        let texels = img
            .pixels()
            .map(|p| {
                let [r, g, b, a] = p.0;
                [
                    linear[r as usize],
                    linear[g as usize],
                    linear[b as usize],
                    quantize(a as f32 / 255.0),
                ]
            })
            .collect();
        Texture {
            width: img.width(),
            height: img.height(),
            texels,
        }
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The texel in column `i`, row `j` (from the top), with wrapping applied to the indices.
    #[inline(always)]
    pub fn texel(&self, i: i64, j: i64, wrap: Wrap) -> [f32; 4] {
        self.texels[self.texel_index(i, j, wrap)].map(|c| c as f32 * (1.0 / TEXEL_MAX))
    }

    #[inline(always)]
    fn texel_index(&self, i: i64, j: i64, wrap: Wrap) -> usize {
        let (w, h) = (self.width as i64, self.height as i64);
        let (i, j) = match wrap {
            Wrap::Clamp => (i.clamp(0, w - 1), j.clamp(0, h - 1)),
            Wrap::Repeat => (i.rem_euclid(w), j.rem_euclid(h)),
        };
        (j * w + i) as usize
    }

    /// Bilinear sample `C_tex` at texture coordinates `uv` (Eq. (6.3)).
    ///
    /// The four taps are the texel centres around `uv`, i.e. `uv ± δ` with `δ = 1/(2N)` per
    /// axis, weighted by `w_pq` (products of the fractional distances, `Σ w_pq = 1`). Exactly
    /// at a texel centre the sample is that texel. Non-finite coordinates (a vertex behind the
    /// camera in projective texturing) give transparent black.
    #[inline]
    pub fn sample(&self, uv: [f64; 2], wrap: Wrap) -> [f32; 4] {
        if !(uv[0].is_finite() && uv[1].is_finite()) {
            return [0.0; 4];
        }
        let x = uv[0] * self.width as f64 - 0.5;
        let y = (1.0 - uv[1]) * self.height as f64 - 0.5;
        // Clamp far-away coordinates before the integer conversion; beyond ±2³⁰ texels any
        // wrap mode has long saturated or repeated.
        let (x, y) = (x.clamp(-1e9, 1e9), y.clamp(-1e9, 1e9));
        // floor without a libm call on baseline x86-64: truncate, then step down for negatives.
        let floor = |v: f64| {
            let t = v as i64;
            t - (t as f64 > v) as i64
        };
        let (i, j) = (floor(x), floor(y));
        let (fx, fy) = ((x - i as f64) as f32, (y - j as f64) as f32);
        let t00 = self.texel(i, j, wrap);
        let t10 = self.texel(i + 1, j, wrap);
        let t01 = self.texel(i, j + 1, wrap);
        let t11 = self.texel(i + 1, j + 1, wrap);
        let (w00, w10, w01, w11) = (
            (1.0 - fx) * (1.0 - fy),
            fx * (1.0 - fy),
            (1.0 - fx) * fy,
            fx * fy,
        );
        std::array::from_fn(|c| w00 * t00[c] + w10 * t10[c] + w01 * t01[c] + w11 * t11[c])
    }

    /// The RGB part of [`Texture::sample`] for the renderer's inner loop: the same taps and
    /// weights, with the wrapped texel columns and rows computed once per sample (not once per
    /// tap) and the 16-bit scale applied once to the weighted sum. Agrees with
    /// [`Texture::sample`] to `f32` rounding (≈ 10⁻⁷).
    #[cfg(test)]
    pub(crate) fn sample_rgb(&self, uv: [f64; 2], wrap: Wrap) -> [f32; 3] {
        let mut taps = TapLanes::default();
        self.taps_at(self.texel_coords(uv), wrap, &mut taps, 0);
        self.blend(&taps, 0)
    }

    /// Texel-space position of texture coordinates `uv`: `(u·W − ½, (1 − v)·H − ½)`, texel
    /// centres at integers. Affine in `uv`, so it can be interpolated instead of `uv`.
    #[inline(always)]
    pub(crate) fn texel_coords(&self, uv: [f64; 2]) -> [f64; 2] {
        [
            uv[0] * self.width as f64 - 0.5,
            (1.0 - uv[1]) * self.height as f64 - 0.5,
        ]
    }

    /// The bilinear taps of [`Texture::sample`] (RGB only) at a texel-space position (see
    /// [`Texture::texel_coords`]) into lane `k` of `taps`; no texel is read. Non-finite
    /// positions give zero weights.
    #[inline(always)]
    fn taps_at(&self, xy: [f64; 2], wrap: Wrap, taps: &mut TapLanes, k: usize) {
        let [x, y] = xy;
        let finite = x.is_finite() && y.is_finite();
        let (w, h) = (self.width as i32, self.height as i32);
        // floor without a libm call on baseline x86-64 (and lane-parallel): truncate, then step
        // down for negatives. Positions are clamped to ±10⁹ first, within `i32`.
        let floor = |v: f64| {
            let t = v as i32;
            t - (t as f64 > v) as i32
        };
        let (i0, i1, j0, j1, fx, fy) = match wrap {
            Wrap::Clamp => {
                // Left of column 0 or right of column W − 1 both taps are the border texel
                // whatever the weights: clamping the position to [-1, W − 1] first leaves the
                // same sample and needs one bound per tap (likewise for rows).
                // Non-finite positions (zero weight below) go to texel (0, 0).
                // (`max`/`min`, not `clamp`, which may panic and so does not vectorise.)
                let (x, y) = if finite {
                    (
                        x.max(-1.0).min((w - 1) as f64),
                        y.max(-1.0).min((h - 1) as f64),
                    )
                } else {
                    (0.0, 0.0)
                };
                // The plain conversion (no saturation or NaN handling) vectorises.
                let floor = |v: f64| {
                    // SAFETY: `v` is finite (non-finite positions were replaced by 0 above)
                    // and clamped between −1 and `W − 1` (or `H − 1`), both `i32` values, so
                    // its truncation is an `i32` as `to_int_unchecked` requires.
                    let t = unsafe { v.to_int_unchecked::<i32>() };
                    t - (t as f64 > v) as i32
                };
                let (i, j) = (floor(x), floor(y));
                let (fx, fy) = ((x - i as f64) as f32, (y - j as f64) as f32);
                (
                    i.max(0),
                    (i + 1).min(w - 1),
                    j.max(0),
                    (j + 1).min(h - 1),
                    fx,
                    fy,
                )
            }
            Wrap::Repeat => {
                // Beyond ±10⁹ texels any position has long repeated.
                let (x, y) = (x.clamp(-1e9, 1e9), y.clamp(-1e9, 1e9));
                let (i, j) = (floor(x), floor(y));
                let (fx, fy) = ((x - i as f64) as f32, (y - j as f64) as f32);
                (
                    i.rem_euclid(w),
                    (i + 1).rem_euclid(w),
                    j.rem_euclid(h),
                    (j + 1).rem_euclid(h),
                    fx,
                    fy,
                )
            }
        };
        let w = w as u64;
        taps.index[k] = j0 as u64 * w + i0 as u64;
        taps.next_column[k] = (i1 - i0) as i64 as u64;
        taps.next_row[k] = ((j1 - j0) as i64 * w as i64) as u64;
        // NaN positions: zero weights (and `NaN as i32 = 0`, a valid texel).
        let (fx, fy) = if finite { (fx, fy) } else { (0.0, 0.0) };
        let s = if finite { 1.0 / TEXEL_MAX } else { 0.0 };
        taps.weight[0][k] = (1.0 - fx) * (1.0 - fy) * s;
        taps.weight[1][k] = fx * (1.0 - fy) * s;
        taps.weight[2][k] = (1.0 - fx) * fy * s;
        taps.weight[3][k] = fx * fy * s;
    }

    /// The RGB sample of lane `k` of `taps`: the weighted sum of its four texels.
    #[inline(always)]
    fn blend(&self, taps: &TapLanes, k: usize) -> [f32; 3] {
        let (i00, di, dj) = (taps.index[k], taps.next_column[k], taps.next_row[k]);
        // Wrapping: a step back to column or row 0 of a repeated texture is "negative".
        let (i10, i01) = (i00.wrapping_add(di), i00.wrapping_add(dj));
        let i11 = i01.wrapping_add(di);
        let texel = |i: u64| self.texels[i as usize];
        let texels = [texel(i00), texel(i10), texel(i01), texel(i11)];
        let weight = [
            taps.weight[0][k],
            taps.weight[1][k],
            taps.weight[2][k],
            taps.weight[3][k],
        ];
        // Tap by tap over all four channels, although alpha is dropped: one SIMD register (one
        // widening conversion and multiply-add per tap). `0 + a` is exact, so the sum is
        // `w₀₀t₀₀ + w₁₀t₁₀ + w₀₁t₀₁ + w₁₁t₁₁` in this order, whichever way it is computed.
        let rgba = weighted_sum(texels, weight);
        [rgba[0], rgba[1], rgba[2]]
    }

    /// The RGB part of [`Texture::sample`] at the first `m` texel-space positions `xy`
    /// (`[axis][lane]`, see [`Texture::texel_coords`]) into `out` (`[channel][lane]`), with
    /// scratch `taps`.
    ///
    /// All taps are located before any texel is read (lane-parallel arithmetic for clamping),
    /// so that the texel loads of the lanes are independent and overlap: sampled one by one,
    /// each sample's cache misses (a large texture does not fit in cache) stalled the work
    /// behind it. At most [`LANES`] positions are sampled.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // `k` indexes several lane arrays
    pub(crate) fn sample_rgb_lanes(
        &self,
        xy: &[[f64; LANES]; 2],
        m: usize,
        wrap: Wrap,
        taps: &mut TapLanes,
        out: &mut [[f32; LANES]; 3],
    ) {
        let m = m.min(LANES);
        // One loop per wrap mode, so that each is branch-free (plain loops: a closure here was
        // compiled out of line, without the caller's wide vectors); the clamped one is
        // lane-parallel. `k < m ≤ LANES` is visible to the compiler here, so the lane stores
        // need no bounds checks and the clamped loop vectorises.
        match wrap {
            Wrap::Clamp => {
                for k in 0..m {
                    self.taps_at([xy[0][k], xy[1][k]], Wrap::Clamp, taps, k);
                }
            }
            Wrap::Repeat => {
                for k in 0..m {
                    self.taps_at([xy[0][k], xy[1][k]], Wrap::Repeat, taps, k);
                }
            }
        }
        // Every lane's two texel rows start loading before the first is read. (Unchecked
        // addresses: a prefetch never faults, so a bounds check per tap would buy nothing.)
        let texels = self.texels.as_ptr();
        for k in 0..m {
            let first = taps.index[k] as usize;
            for index in [first, first.wrapping_add(taps.next_row[k] as usize)] {
                prefetch(texels.wrapping_add(index));
            }
        }
        let [r, g, b] = out;
        for (k, ((r, g), b)) in r[..m]
            .iter_mut()
            .zip(&mut g[..m])
            .zip(&mut b[..m])
            .enumerate()
        {
            [*r, *g, *b] = self.blend(taps, k);
        }
    }
}

/// Bilinear taps of [`LANES`] samples (structure of arrays) after wrapping: the texel index of
/// tap `(i, j)` and the steps to columns `i + 1` and rows `j + 1` (0 at a clamped border,
/// negative — wrapped in `u64` — at a repeated one), and the weights of the taps `(i, j)`,
/// `(i + 1, j)`, `(i, j + 1)`, `(i + 1, j + 1)` with the 16-bit scale folded in (all 0 for a
/// non-finite position). Scratch of [`Texture::sample_rgb_lanes`].
pub(crate) struct TapLanes {
    index: [u64; LANES],
    next_column: [u64; LANES],
    next_row: [u64; LANES],
    weight: [[f32; LANES]; 4],
}

impl Default for TapLanes {
    fn default() -> Self {
        TapLanes {
            index: [0; LANES],
            next_column: [0; LANES],
            next_row: [0; LANES],
            weight: [[0.0; LANES]; 4],
        }
    }
}

/// `Σ weights[k] · texels[k]` in tap order `k`, per channel, starting from `0`.
///
/// On x86-64 in one SSE2 register (part of the baseline): the compiler left one channel scalar
/// and the widening to lanes by hand halves the instructions of the sum. Lane-wise IEEE
/// multiplies and adds in the same order, so the value is that of the scalar loop.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn weighted_sum(texels: [[u16; 4]; 4], weights: [f32; 4]) -> [f32; 4] {
    use std::arch::x86_64::{
        __m128, _mm_add_ps, _mm_cvtepi32_ps, _mm_cvtsi64_si128, _mm_mul_ps, _mm_set1_ps,
        _mm_setzero_ps, _mm_setzero_si128, _mm_unpacklo_epi16,
    };
    // SAFETY: SSE and SSE2 are part of the x86-64 baseline, so these intrinsics are always
    // available; `__m128` and `[f32; 4]` have the same size and every bit pattern is valid.
    unsafe {
        let mut acc = _mm_setzero_ps();
        for (texel, weight) in texels.into_iter().zip(weights) {
            let bits = texel
                .iter()
                .enumerate()
                .fold(0u64, |b, (c, &t)| b | u64::from(t) << (16 * c));
            // Zero-extend the four u16 to i32 lanes, exactly to f32.
            let lanes = _mm_unpacklo_epi16(_mm_cvtsi64_si128(bits as i64), _mm_setzero_si128());
            acc = _mm_add_ps(acc, _mm_mul_ps(_mm_set1_ps(weight), _mm_cvtepi32_ps(lanes)));
        }
        std::mem::transmute::<__m128, [f32; 4]>(acc)
    }
}

/// `Σ weights[k] · texels[k]` in tap order `k`, per channel, starting from `0`.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn weighted_sum(texels: [[u16; 4]; 4], weights: [f32; 4]) -> [f32; 4] {
    let mut rgba = [0.0f32; 4];
    for (texel, weight) in texels.into_iter().zip(weights) {
        for c in 0..4 {
            rgba[c] += weight * texel[c] as f32;
        }
    }
    rgba
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> Texture {
        // 4×2 texels, red = column / 4, green = row / 2.
        let texels = (0..8)
            .map(|k| [(k % 4) as f32 / 4.0, (k / 4) as f32 / 2.0, 0.0, 1.0])
            .collect();
        Texture::new(4, 2, texels).unwrap()
    }

    #[test]
    fn texel_centres_are_exact_and_midpoints_average() {
        let t = ramp();
        // Centre of texel (2, 1): u = 2.5/4, v = 1 − 1.5/2.
        let centre = t.sample([2.5 / 4.0, 0.25], Wrap::Clamp);
        assert_eq!(centre, t.texel(2, 1, Wrap::Clamp));
        let expected = [0.5, 0.5, 0.0, 1.0];
        assert!(
            (0..4).all(|c| (centre[c] - expected[c]).abs() < 1e-4),
            "{centre:?}"
        );
        // Half-way between columns 1 and 2 and between rows 0 and 1.
        let s = t.sample([0.5, 0.5], Wrap::Clamp);
        assert!((s[0] - 1.5 / 4.0).abs() < 1e-5 && (s[1] - 0.25).abs() < 1e-5);
        // Bilinear is affine inside a cell: the red ramp is linear in u.
        let s = t.sample([0.3, 0.75], Wrap::Clamp);
        assert!((s[0] - (0.3 * 4.0 - 0.5) as f32 / 4.0).abs() < 1e-5);
    }

    #[test]
    fn fast_rgb_sampling_agrees_with_sample() {
        let t = ramp();
        for wrap in [Wrap::Clamp, Wrap::Repeat] {
            for k in 0..400 {
                let uv = [-1.3 + 0.0137 * k as f64, 2.1 - 0.0113 * k as f64];
                let (a, b) = (t.sample(uv, wrap), t.sample_rgb(uv, wrap));
                assert!(
                    (0..3).all(|c| (a[c] - b[c]).abs() < 1e-6),
                    "{uv:?}: {a:?} vs {b:?}"
                );
            }
        }
        assert_eq!(t.sample_rgb([f64::INFINITY, 0.5], Wrap::Repeat), [0.0; 3]);
    }

    /// The renderer's lane sampler (taps located for a block, prefetched, then blended; the
    /// clamped floor is an unchecked conversion) against [`Texture::sample`], lane by lane: both
    /// wraps, positions far outside the texture and non-finite ones, full and partial blocks.
    #[test]
    fn lane_sampling_agrees_with_sample() {
        let texels = (0..15)
            .map(|k| [(k % 5) as f32 / 5.0, (k / 5) as f32 / 3.0, 0.25, 1.0])
            .collect();
        let t = Texture::new(5, 3, texels).unwrap();
        let special = [
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
            1e12,
            -1e12,
            0.0,
            1.0,
        ];
        let mut uvs: Vec<[f64; 2]> = (0..2 * LANES + 7)
            .map(|k| [-2.3 + 0.0371 * k as f64, 3.1 - 0.0297 * k as f64])
            .collect();
        uvs.extend(special.iter().flat_map(|&u| special.map(|v| [u, v])));
        let mut taps = TapLanes::default();
        for wrap in [Wrap::Clamp, Wrap::Repeat] {
            for block in uvs.chunks(LANES) {
                let m = block.len();
                let mut xy = [[0.0; LANES]; 2];
                for (l, &uv) in block.iter().enumerate() {
                    [xy[0][l], xy[1][l]] = t.texel_coords(uv);
                }
                let mut out = [[f32::NAN; LANES]; 3];
                t.sample_rgb_lanes(&xy, m, wrap, &mut taps, &mut out);
                for (l, &uv) in block.iter().enumerate() {
                    let want = t.sample(uv, wrap);
                    let got = [out[0][l], out[1][l], out[2][l]];
                    assert!(
                        (0..3).all(|c| (got[c] - want[c]).abs() < 1e-6),
                        "{wrap:?} {uv:?}: {got:?} vs {want:?}"
                    );
                }
                assert!(out.iter().all(|c| c[m..].iter().all(|v| v.is_nan())));
            }
        }
    }

    #[test]
    fn clamp_and_repeat_differ_outside_the_unit_square() {
        let t = ramp();
        assert_eq!(t.sample([-3.0, 0.75], Wrap::Clamp)[0], 0.0);
        let a = t.sample([0.125 + 1.0, 0.75], Wrap::Repeat);
        let b = t.sample([0.125, 0.75], Wrap::Repeat);
        assert_eq!(a, b);
        // Between the last and the first column, repeat blends them, clamp does not.
        assert!((t.sample([1.0, 0.75], Wrap::Repeat)[0] - 1.5 / 4.0).abs() < 1e-5);
        assert!((t.sample([1.0, 0.75], Wrap::Clamp)[0] - 0.75).abs() < 1e-4);
        assert_eq!(t.sample([f64::NAN, 0.5], Wrap::Clamp), [0.0; 4]);
        assert!(Texture::new(2, 2, vec![[0.0; 4]; 3]).is_err());
        assert!(Texture::new(1, 1, vec![[0.0, f32::NAN, 0.0, 1.0]]).is_err());
        assert!(Texture::new(1, 1, vec![[0.0, 1.5, 0.0, 1.0]]).is_err());
    }
}
