//! Bilinear sampling of an RGB8 frame into a network's float input, the way MediaPipe's crops
//! read their frames: one point at a time ([`sample_rgb`]) or eight ([`sample_rgb_lanes`], with
//! AVX2 gathers where the CPU has them; the same values bit for bit).

/// The RGB value at `(fx, fy)` (pixel centres at integers, inside the image) of the `w × h`
/// RGB8 image `src`, bilinearly interpolated and scaled to [0, 1], into `out[..3]`.
///
/// # Panics
/// If a neighbour of `(fx, fy)` lies outside `src`.
#[inline(always)]
pub fn sample_rgb(src: &[u8], w: usize, h: usize, fx: f32, fy: f32, out: &mut [f32]) {
    // `as usize` truncates and saturates (negative and NaN to 0), so for every f32 it gives
    // what `floor()` then `as usize` gave, without a call into libm (x86-64's baseline has no
    // rounding instruction).
    let (x0, y0) = (fx as usize, fy as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (ax, ay) = (fx - x0 as f32, fy - y0 as f32);
    // The four neighbours' RGB, each one bounds check.
    let px = |xx: usize, yy: usize| -> [f32; 3] {
        let i = (yy * w + xx) * 3;
        let p: &[u8; 3] = src[i..i + 3].try_into().expect("three bytes");
        p.map(f32::from)
    };
    let (p00, p10, p01, p11) = (px(x0, y0), px(x1, y0), px(x0, y1), px(x1, y1));
    for (ch, o) in out.iter_mut().take(3).enumerate() {
        let top = p00[ch] + ax * (p10[ch] - p00[ch]);
        let bottom = p01[ch] + ax * (p11[ch] - p01[ch]);
        *o = (top + ay * (bottom - top)) * (1.0 / 255.0);
    }
}

/// [`sample_rgb`] at eight points `(fx[k], fy[k])`, into `out[3k .. 3k + 3]`.
///
/// # Panics
/// As [`sample_rgb`].
#[inline]
pub fn sample_rgb_lanes(
    src: &[u8],
    w: usize,
    h: usize,
    fx: &[f32; 8],
    fy: &[f32; 8],
    out: &mut [f32; 24],
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2")
        && w > 0
        && h > 0
        && src.len() == w * h * 3
        && src.len() < i32::MAX as usize
        && w.max(h) < 1 << 24
    {
        // SAFETY: the CPU has AVX2 (tested just above).
        #[allow(unsafe_code)]
        if unsafe { avx2::sample8(src, w, fx, fy, out) } {
            return;
        }
    }
    for (k, o) in out.chunks_exact_mut(3).enumerate() {
        sample_rgb(src, w, h, fx[k], fy[k], o);
    }
}

/// [`sample_rgb`] for eight points with AVX2: the four neighbours' RGB bytes by 32-bit gathers
/// (the byte after each pixel comes along and is dropped), the same operations in the same
/// order without fused multiply-adds, so the same values.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod avx2 {
    use std::arch::x86_64::{
        __m256, __m256i, _mm256_add_epi32, _mm256_add_ps, _mm256_and_si256, _mm256_cvtepi32_ps,
        _mm256_cvttps_epi32, _mm256_i32gather_epi32, _mm256_loadu_ps, _mm256_min_epi32,
        _mm256_mul_ps, _mm256_mullo_epi32, _mm256_set1_epi32, _mm256_set1_ps, _mm256_srli_epi32,
        _mm256_storeu_ps, _mm256_sub_ps,
    };

    /// Whether [`sample8`] may read these points of a `w × h` image: every coordinate inside
    /// `[0, w − 1]` × `[0, h − 1]` (so not NaN), and four bytes readable at each neighbour (the
    /// last pixel of the image has only three: such points go the scalar way). Branch-free, so
    /// that it compiles to vector compares.
    #[inline(always)]
    fn fits(w: usize, h: usize, fx: &[f32; 8], fy: &[f32; 8]) -> bool {
        let (max_x, max_y) = ((w - 1) as f32, (h - 1) as f32);
        // x1 = w − 1 exactly where ⌊x⌋ ≥ w − 2, i.e. x ≥ w − 2 (exact below 2²⁴ pixels).
        let (last_x, last_y) = (w as f32 - 2.0, h as f32 - 2.0);
        let mut ok = true;
        for (&x, &y) in fx.iter().zip(fy) {
            let inside = (x >= 0.0) & (x <= max_x) & (y >= 0.0) & (y <= max_y);
            // The farthest byte read is the fourth of neighbour (x1, y1): inside the image
            // unless that neighbour is its last pixel (x1 = w − 1 and y1 = h − 1).
            let tail = (x < last_x) | (y < last_y);
            ok &= inside & tail;
        }
        ok
    }

    /// The eight samples into `out` where the points [`fits`] the image `src` (`w` pixels wide,
    /// `w > 0`, three bytes a pixel, fewer than `i32::MAX` bytes, sides below 2²⁴: the caller
    /// checks); `false`, with `out` untouched, where they do not.
    #[target_feature(enable = "avx2")]
    pub(super) fn sample8(
        src: &[u8],
        w: usize,
        fx: &[f32; 8],
        fy: &[f32; 8],
        out: &mut [f32; 24],
    ) -> bool {
        let h = src.len() / 3 / w;
        if h == 0 || !fits(w, h, fx, fy) {
            return false;
        }
        // SAFETY: fx and fy hold eight values each.
        let (vx, vy) = unsafe { (_mm256_loadu_ps(fx.as_ptr()), _mm256_loadu_ps(fy.as_ptr())) };
        // Coordinates in [0, max] (checked): truncation is `as usize`.
        let (x0, y0) = (_mm256_cvttps_epi32(vx), _mm256_cvttps_epi32(vy));
        let one = _mm256_set1_epi32(1);
        let x1 = _mm256_min_epi32(_mm256_add_epi32(x0, one), _mm256_set1_epi32(w as i32 - 1));
        let y1 = _mm256_min_epi32(_mm256_add_epi32(y0, one), _mm256_set1_epi32(h as i32 - 1));
        let ax = _mm256_sub_ps(vx, _mm256_cvtepi32_ps(x0));
        let ay = _mm256_sub_ps(vy, _mm256_cvtepi32_ps(y0));
        let (wv, three) = (_mm256_set1_epi32(w as i32), _mm256_set1_epi32(3));
        let offset = |xx: __m256i, yy: __m256i| {
            _mm256_mullo_epi32(_mm256_add_epi32(_mm256_mullo_epi32(yy, wv), xx), three)
        };
        let base = src.as_ptr() as *const i32;
        // SAFETY: every offset is a pixel of the image with a fourth byte after it inside
        // `src` (`fits`), and below i32::MAX (the caller's check).
        let gather = |off: __m256i| unsafe { _mm256_i32gather_epi32::<1>(base, off) };
        let (g00, g10) = (gather(offset(x0, y0)), gather(offset(x1, y0)));
        let (g01, g11) = (gather(offset(x0, y1)), gather(offset(x1, y1)));
        let byte = _mm256_set1_epi32(0xff);
        let channel = |g: __m256i, ch: i32| -> __m256 {
            let shifted = match ch {
                0 => g,
                1 => _mm256_srli_epi32::<8>(g),
                _ => _mm256_srli_epi32::<16>(g),
            };
            _mm256_cvtepi32_ps(_mm256_and_si256(shifted, byte))
        };
        let scale = _mm256_set1_ps(1.0 / 255.0);
        let mut planes = [[0.0f32; 8]; 3];
        for (ch, plane) in planes.iter_mut().enumerate() {
            let (p00, p10) = (channel(g00, ch as i32), channel(g10, ch as i32));
            let (p01, p11) = (channel(g01, ch as i32), channel(g11, ch as i32));
            let top = _mm256_add_ps(p00, _mm256_mul_ps(ax, _mm256_sub_ps(p10, p00)));
            let bottom = _mm256_add_ps(p01, _mm256_mul_ps(ax, _mm256_sub_ps(p11, p01)));
            let v = _mm256_mul_ps(
                _mm256_add_ps(top, _mm256_mul_ps(ay, _mm256_sub_ps(bottom, top))),
                scale,
            );
            // SAFETY: `plane` holds eight values.
            unsafe { _mm256_storeu_ps(plane.as_mut_ptr(), v) };
        }
        for (k, o) in out.chunks_exact_mut(3).enumerate() {
            o.copy_from_slice(&[planes[0][k], planes[1][k], planes[2][k]]);
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eight points at a time give the one-point values bit for bit, inside the image, at its
    /// last row and column (the scalar way there) and at its corners.
    #[test]
    fn lanes_match_single_points() {
        let (w, h) = (13, 9);
        let src: Vec<u8> = (0..w * h * 3).map(|i| (i * 37 % 251) as u8).collect();
        let (mx, my) = ((w - 1) as f32, (h - 1) as f32);
        let sets: [([f32; 8], [f32; 8]); 4] = [
            (
                [0.0, 0.3, 1.7, 5.5, 11.99, 12.0, 7.25, 3.0],
                [0.0, 0.9, 2.2, 4.5, 6.01, 3.3, 7.5, 1.0],
            ),
            ([mx; 8], [my; 8]),
            (
                [0.5, mx, 11.5, 10.0, 0.0, 2.0, 3.0, mx - 0.5],
                [my - 0.5; 8],
            ),
            ([6.0; 8], [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]),
        ];
        for (fx, fy) in sets {
            let mut lanes = [0.0; 24];
            sample_rgb_lanes(&src, w, h, &fx, &fy, &mut lanes);
            for k in 0..8 {
                let mut one = [0.0; 3];
                sample_rgb(&src, w, h, fx[k], fy[k], &mut one);
                for ch in 0..3 {
                    assert_eq!(lanes[3 * k + ch].to_bits(), one[ch].to_bits(), "point {k}");
                }
            }
        }
    }
}
