//! Bilinear sampling of an RGB8 image, the way the networks' crops read their frames.

/// The RGB value at `(fx, fy)` (pixel centres at integers, inside the image) of the `w × h`
/// RGB8 image `src`, bilinearly interpolated and scaled to [0, 1], into `out[..3]`.
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
