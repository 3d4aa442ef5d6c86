//! Sampling the rotated square ROI into the landmark network's input (MediaPipe's
//! `ImageToTensorCalculator` with a rotated rect: bilinear, border replicated, RGB in [0, 1]).

use image::RgbImage;

use crate::Roi;
use visage_nn::bilinear::{sample_rgb, sample_rgb_lanes};

/// Fills `out` (`side × side × 3`, row-major RGB) with the ROI of `image`, values `pixel / 255`.
///
/// Output pixel `(i, j)` samples the frame at `roi.to_frame(i/side, j/side)` read as
/// pixel-centre coordinates, bilinearly, with coordinates clamped to the image (replicated
/// border). This is exactly what MediaPipe does (OpenCV `getPerspectiveTransform` from the box
/// corners to the output corners, then `warpPerspective` with `INTER_LINEAR`): it shifts the
/// content by `(scale − 1)/2` frame pixels relative to a centre-aligned resampling, and
/// MediaPipe's reported landmarks carry that shift. Reproducing it is what makes the output
/// agree with MediaPipe's (`shared/reference/facemesh/*/solution.json`).
///
/// # Panics
/// If `out.len() != side · side · 3` or the image is empty.
#[track_caller]
pub fn crop_roi(image: &RgbImage, roi: &Roi, side: usize, out: &mut [f32]) {
    assert_eq!(out.len(), side * side * 3, "crop buffer size");
    let (w, h) = (image.width() as usize, image.height() as usize);
    assert!(w > 0 && h > 0, "empty image");
    let src = image.as_raw();
    let (s, c) = roi.rotation.sin_cos();
    let inv = 1.0 / side as f32;
    let max_x = (w - 1) as f32;
    let max_y = (h - 1) as f32;
    let at = |i: usize, y: f32| {
        let x = i as f32 * inv - 0.5;
        let fx = (roi.center[0] + (c * x - s * y) * roi.size).clamp(0.0, max_x);
        let fy = (roi.center[1] + (s * x + c * y) * roi.size).clamp(0.0, max_y);
        (fx, fy)
    };
    for (j, row) in out.chunks_exact_mut(side * 3).enumerate() {
        let y = j as f32 * inv - 0.5;
        // Eight pixels at a time, then the rest one by one.
        let mut lanes = row.chunks_exact_mut(24);
        for (k, o) in (&mut lanes).enumerate() {
            let (mut fx, mut fy) = ([0.0; 8], [0.0; 8]);
            for q in 0..8 {
                (fx[q], fy[q]) = at(8 * k + q, y);
            }
            let o: &mut [f32; 24] = o.try_into().expect("24 values");
            sample_rgb_lanes(src, w, h, &fx, &fy, o);
        }
        let done = side / 8 * 8;
        for (q, o) in lanes.into_remainder().chunks_exact_mut(3).enumerate() {
            let (fx, fy) = at(done + q, y);
            sample_rgb(src, w, h, fx, fy, o);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_crop_reproduces_the_image() {
        let img = RgbImage::from_fn(8, 8, |x, y| image::Rgb([(x * 30) as u8, (y * 30) as u8, 7]));
        let roi = Roi {
            center: [4.0, 4.0],
            size: 8.0,
            rotation: 0.0,
        };
        // Corner-aligned: output pixel i samples input i exactly when the scale is 1.
        let mut out = vec![0.0; 8 * 8 * 3];
        crop_roi(&img, &roi, 8, &mut out);
        for (a, &b) in out.iter().zip(img.as_raw()) {
            assert!((a * 255.0 - b as f32).abs() < 1e-3);
        }
        // A half-turn flips the image.
        let roi = Roi {
            rotation: std::f32::consts::PI,
            ..roi
        };
        crop_roi(&img, &roi, 8, &mut out);
        // Pixel 0 samples 8 − 0 clamped to 7.
        assert!((out[0] * 255.0 - 210.0).abs() < 1e-2 && (out[1] * 255.0 - 210.0).abs() < 1e-2);
    }
}
