//! Bilinear sampling of an RGB8 image, the way the networks' crops read their frames.

/// The RGB value at `(fx, fy)` (pixel centres at integers, inside the image) of the `w × h`
/// RGB8 image `src`, bilinearly interpolated and scaled to [0, 1], into `out[..3]`.
#[inline]
pub fn sample_rgb(src: &[u8], w: usize, h: usize, fx: f32, fy: f32, out: &mut [f32]) {
    let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (ax, ay) = (fx - x0 as f32, fy - y0 as f32);
    for (ch, o) in out.iter_mut().take(3).enumerate() {
        let p = |xx: usize, yy: usize| src[(yy * w + xx) * 3 + ch] as f32;
        let top = p(x0, y0) + ax * (p(x1, y0) - p(x0, y0));
        let bottom = p(x0, y1) + ax * (p(x1, y1) - p(x0, y1));
        *o = (top + ay * (bottom - top)) * (1.0 / 255.0);
    }
}
