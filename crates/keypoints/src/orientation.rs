//! Dominant orientations (paper §3, the 36-bin histogram; Lowe 2004 §5): gradient directions
//! around the keypoint, weighted by magnitude and a Gaussian of 1.5 × the keypoint's scale,
//! smoothed, and every peak within 80 % of the highest (parabola-interpolated) as a keypoint.

use crate::descriptor::GradientSamples;
use crate::GrayImage;

/// Bins of the orientation histogram (10° each).
pub const ORIENTATION_BINS: usize = 36;

/// Gaussian window σ in units of the keypoint's scale (Lowe's 1.5).
const WINDOW_SIGMA_FACTOR: f32 = 1.5;

/// Window radius in window σ's (OpenCV's `SIFT_ORI_RADIUS` = 3 × 1.5 scales).
const WINDOW_RADIUS_FACTOR: f32 = 3.0 * WINDOW_SIGMA_FACTOR;

/// Secondary peaks at least this fraction of the highest give keypoints of their own.
pub const PEAK_RATIO: f32 = 0.8;

/// The orientation histogram of `image` around the integer sample `(c, r)` for a keypoint of
/// scale `scale` (level pixels), smoothed with the `[1 4 6 4 1] / 16` kernel. Bins hold angles
/// of `atan2(−∂y, ∂x)` (image rows point down, so angles run counter-clockwise on screen).
pub fn orientation_histogram(
    image: &GrayImage,
    c: usize,
    r: usize,
    scale: f32,
    samples: &mut GradientSamples,
) -> [f32; ORIENTATION_BINS] {
    let n = ORIENTATION_BINS;
    let radius = (WINDOW_RADIUS_FACTOR * scale).round() as isize;
    let sigma = WINDOW_SIGMA_FACTOR * scale;
    let exp_scale = -1.0 / (2.0 * sigma * sigma);
    let (w, h) = (image.width() as isize, image.height() as isize);
    samples.clear();
    for i in -radius..=radius {
        let y = r as isize + i;
        if y <= 0 || y >= h - 1 {
            continue;
        }
        let (above, row, below) = (
            image.row(y as usize - 1),
            image.row(y as usize),
            image.row(y as usize + 1),
        );
        for j in -radius..=radius {
            let x = c as isize + j;
            if x <= 0 || x >= w - 1 {
                continue;
            }
            let x = x as usize;
            samples.dx.push(row[x + 1] - row[x - 1]);
            samples.dy.push(above[x] - below[x]);
            samples.weight.push(((i * i + j * j) as f32) * exp_scale);
        }
    }
    samples.weigh();
    let bins_per_degree = n as f32 / 360.0;
    let mut raw = [0.0f32; ORIENTATION_BINS];
    for (&angle, &weight) in samples.angle.iter().zip(&samples.weight) {
        // Nearest bin; angles are in [0, 360), so truncation of `+ 0.5` rounds.
        let bin = (bins_per_degree * angle + 0.5) as usize;
        raw[if bin >= n { bin - n } else { bin }] += weight;
    }
    let mut hist = [0.0f32; ORIENTATION_BINS];
    for (k, out) in hist.iter_mut().enumerate() {
        let at = |d: isize| raw[(k as isize + d).rem_euclid(n as isize) as usize];
        *out = (at(-2) + at(2)) * (1.0 / 16.0)
            + (at(-1) + at(1)) * (4.0 / 16.0)
            + at(0) * (6.0 / 16.0);
    }
    hist
}

/// The keypoint angles (degrees in `[0, 360)`, OpenCV's convention `360° − θ`) of the
/// histogram's peaks that reach [`PEAK_RATIO`] of its maximum, each refined by a parabola
/// through the peak and its neighbours.
pub fn peak_angles(hist: &[f32; ORIENTATION_BINS], out: &mut Vec<f32>) {
    out.clear();
    let n = ORIENTATION_BINS;
    let max = hist.iter().copied().fold(0.0f32, f32::max);
    let threshold = max * PEAK_RATIO;
    for j in 0..n {
        let l = hist[(j + n - 1) % n];
        let r = hist[(j + 1) % n];
        let v = hist[j];
        if v > l && v > r && v >= threshold {
            let mut bin = j as f32 + 0.5 * (l - r) / (l - 2.0 * v + r);
            if bin < 0.0 {
                bin += n as f32;
            } else if bin >= n as f32 {
                bin -= n as f32;
            }
            let mut angle = 360.0 - (360.0 / n as f32) * bin;
            if (angle - 360.0).abs() < f32::EPSILON * 360.0 {
                angle = 0.0;
            }
            out.push(angle);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear ramp whose intensity increases along direction `theta` (image x right, y
    /// down).
    fn ramp(theta_deg: f32) -> GrayImage {
        let (w, h) = (41, 41);
        let (cs, sn) = (theta_deg.to_radians().cos(), theta_deg.to_radians().sin());
        let data = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x as f32, y as f32)))
            .map(|(x, y)| 100.0 + 2.0 * ((x - 20.0) * cs + (y - 20.0) * sn))
            .collect();
        GrayImage::from_vec(w, h, data).unwrap()
    }

    #[test]
    fn the_angle_of_a_ramp_follows_its_rotation() {
        let mut angles = Vec::new();
        for theta in [0.0f32, 25.0, 90.0, 133.0, 200.0, 311.0] {
            let hist =
                orientation_histogram(&ramp(theta), 20, 20, 2.0, &mut GradientSamples::default());
            peak_angles(&hist, &mut angles);
            assert_eq!(angles.len(), 1, "θ = {theta}: {angles:?}");
            // Gradient along +θ in image axes (y down) is atan2(−sin θ, cos θ) = −θ in the
            // histogram, which OpenCV reports as 360° − (−θ) = θ.
            let err = (angles[0] - theta).rem_euclid(360.0);
            let err = err.min(360.0 - err);
            // A pure ramp puts all its mass in one or two 10° bins: half a bin is the
            // histogram's resolution for a single direction.
            assert!(err <= 5.0, "θ = {theta}: got {}", angles[0]);
        }
    }

    #[test]
    fn two_equal_peaks_give_two_angles() {
        let mut hist = [0.0f32; ORIENTATION_BINS];
        hist[5] = 10.0;
        hist[4] = 3.0;
        hist[6] = 3.0;
        hist[20] = 9.0;
        hist[19] = 1.0;
        hist[21] = 2.0;
        hist[30] = 7.0; // below 80 % of the maximum
        let mut angles = Vec::new();
        peak_angles(&hist, &mut angles);
        assert_eq!(angles.len(), 2);
        assert!((angles[0] - (360.0 - 50.0)).abs() < 1e-4);
    }
}
