//! Letter-boxing and area-averaging resize of a frame into the detector's square input, as
//! MediaPipe's `ImageToTensorCalculator` with `keep_aspect_ratio: true` and zero borders.

use image::RgbImage;

/// Where the frame sits inside the square canvas that is resized to the detector input:
/// canvas side `side = max(width, height)` pixels, frame placed at `(offset_x, offset_y)`
/// (black bars split evenly, the extra pixel after).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Letterbox {
    pub side: u32,
    pub offset_x: u32,
    pub offset_y: u32,
}

impl Letterbox {
    /// The letter-box of a `width × height` frame.
    pub fn for_frame(width: u32, height: u32) -> Letterbox {
        let side = width.max(height);
        Letterbox {
            side,
            offset_x: (side - width) / 2,
            offset_y: (side - height) / 2,
        }
    }

    /// Maps a point normalised to the square input (`[0, 1]²`, edges at 0 and 1) to frame
    /// pixels with pixel `(i, j)` covering `[i, i+1) × [j, j+1)` (MediaPipe's convention).
    pub fn to_frame(&self, p: [f32; 2]) -> [f32; 2] {
        let s = self.side as f32;
        [
            p[0] * s - self.offset_x as f32,
            p[1] * s - self.offset_y as f32,
        ]
    }
}

/// Letter-boxes `image` into a `size × size` RGB8 buffer (row-major, 3 bytes per pixel) with
/// area averaging (each output pixel is the mean of the canvas area it covers; bars are black),
/// rounded to 8 bits. Returns the letter-box geometry.
pub fn letterbox_resize(image: &RgbImage, size: usize, out: &mut Vec<u8>) -> Letterbox {
    let (w, h) = (image.width() as usize, image.height() as usize);
    let lb = Letterbox::for_frame(image.width(), image.height());
    let cols = area_weights(lb.side as usize, size, lb.offset_x as usize, w);
    let rows = area_weights(lb.side as usize, size, lb.offset_y as usize, h);
    // Horizontal pass over the frame's rows: h × size × 3.
    let src = image.as_raw();
    let mut tmp = vec![0.0f32; h * size * 3];
    for y in 0..h {
        let row = &src[y * w * 3..(y + 1) * w * 3];
        for (i, taps) in cols.iter().enumerate() {
            let mut acc = [0.0f32; 3];
            for &(x, wt) in taps {
                for c in 0..3 {
                    acc[c] += wt * row[x * 3 + c] as f32;
                }
            }
            tmp[(y * size + i) * 3..(y * size + i) * 3 + 3].copy_from_slice(&acc);
        }
    }
    out.clear();
    out.resize(size * size * 3, 0);
    for (j, taps) in rows.iter().enumerate() {
        for i in 0..size {
            let mut acc = [0.0f32; 3];
            for &(y, wt) in taps {
                for c in 0..3 {
                    acc[c] += wt * tmp[(y * size + i) * 3 + c];
                }
            }
            for c in 0..3 {
                out[(j * size + i) * 3 + c] = acc[c].round().clamp(0.0, 255.0) as u8;
            }
        }
    }
    lb
}

/// Letter-boxes `image` into a `size × size` RGB8 buffer by bilinear sampling, as MediaPipe's
/// CPU `ImageToTensorCalculator` (OpenCV `warpAffine`, `INTER_LINEAR`, zero border): output
/// pixel `(i, j)` samples the canvas at `(i·side/size, j·side/size)` (corner-aligned, as
/// MediaPipe's perspective transform from the canvas corners).
pub fn letterbox_bilinear(image: &RgbImage, size: usize, out: &mut Vec<u8>) -> Letterbox {
    let (w, h) = (image.width() as i64, image.height() as i64);
    let lb = Letterbox::for_frame(image.width(), image.height());
    let scale = lb.side as f32 / size as f32;
    let src = image.as_raw();
    out.clear();
    out.resize(size * size * 3, 0);
    let px = |x: i64, y: i64, c: usize| -> f32 {
        if x < 0 || y < 0 || x >= w || y >= h {
            0.0
        } else {
            src[((y * w + x) * 3) as usize + c] as f32
        }
    };
    for j in 0..size {
        let fy = j as f32 * scale - lb.offset_y as f32;
        let y0 = fy.floor();
        let ay = fy - y0;
        for i in 0..size {
            let fx = i as f32 * scale - lb.offset_x as f32;
            let x0 = fx.floor();
            let ax = fx - x0;
            let (x0, y0) = (x0 as i64, y0 as i64);
            for c in 0..3 {
                let top = px(x0, y0, c) * (1.0 - ax) + px(x0 + 1, y0, c) * ax;
                let bottom = px(x0, y0 + 1, c) * (1.0 - ax) + px(x0 + 1, y0 + 1, c) * ax;
                out[(j * size + i) * 3 + c] =
                    (top * (1.0 - ay) + bottom * ay).round().clamp(0.0, 255.0) as u8;
            }
        }
    }
    lb
}

/// For each of `dst` output pixels along one axis of a canvas of `canvas` pixels, the frame
/// pixels (`0..len`, placed at `offset`) it overlaps and their weights (overlap / output
/// pixel extent; canvas pixels outside the frame are black and contribute nothing).
fn area_weights(canvas: usize, dst: usize, offset: usize, len: usize) -> Vec<Vec<(usize, f32)>> {
    let scale = canvas as f64 / dst as f64;
    (0..dst)
        .map(|i| {
            let (a, b) = (i as f64 * scale, (i + 1) as f64 * scale);
            let mut taps = Vec::new();
            let first = a.floor() as usize;
            let last = (b.ceil() as usize).min(canvas);
            for p in first..last {
                let overlap = (b.min(p as f64 + 1.0) - a.max(p as f64)).max(0.0);
                if overlap <= 0.0 || p < offset || p >= offset + len {
                    continue;
                }
                taps.push((p - offset, (overlap / scale) as f32));
            }
            taps
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geometry_and_constant_image() {
        let lb = Letterbox::for_frame(720, 1280);
        assert_eq!((lb.side, lb.offset_x, lb.offset_y), (1280, 280, 0));
        assert_eq!(lb.to_frame([0.5, 0.5]), [360.0, 640.0]);
        let img = RgbImage::from_pixel(64, 32, image::Rgb([200, 100, 50]));
        let mut out = Vec::new();
        let lb = letterbox_resize(&img, 16, &mut out);
        assert_eq!((lb.side, lb.offset_y), (64, 16));
        // Rows 0..4 are the top bar, 4..12 the image, 12..16 the bottom bar.
        assert_eq!(&out[0..3], &[0, 0, 0]);
        assert_eq!(
            &out[(8 * 16 + 5) * 3..(8 * 16 + 5) * 3 + 3],
            &[200, 100, 50]
        );
        assert_eq!(&out[(15 * 16) * 3..(15 * 16) * 3 + 3], &[0, 0, 0]);
        // Upscaling a tiny image works too.
        let tiny = RgbImage::from_pixel(3, 2, image::Rgb([10, 20, 30]));
        letterbox_resize(&tiny, 128, &mut out);
        assert_eq!(
            &out[(64 * 128 + 64) * 3..(64 * 128 + 64) * 3 + 3],
            &[10, 20, 30]
        );
    }
}
