//! The 128-D SIFT descriptor (paper §3 "spatial pooling"; Lowe 2004 §6): gradients in a
//! window rotated to the keypoint's orientation, weighted by a Gaussian of half the window,
//! binned trilinearly into 4 × 4 cells × 8 orientations, normalised, clipped at 0.2,
//! renormalised and stored as bytes (× 512, saturated) the way OpenCV stores them.

use crate::fast_math::{atan2_degrees, exp_nonpositive};
use crate::{Descriptor, GrayImage, DESCRIPTOR_LEN};

/// Cells per side of the descriptor grid.
pub const GRID: usize = 4;

/// Orientation bins per cell.
pub const CELL_BINS: usize = 8;

/// Cell width in units of the keypoint's scale (Lowe's 3σ; the window is 4 cells wide).
const CELL_WIDTH_FACTOR: f32 = 3.0;

/// Normalised entries are clipped at this value (Lowe's 0.2) before renormalising.
pub const CLIP: f32 = 0.2;

/// The renormalised vector is stored as `round(512 · v)` saturated to a byte.
const BYTE_SCALE: f32 = 512.0;

/// Histogram with a margin of one cell on each side and two extra orientation bins, so the
/// trilinear spreading needs no bounds checks (OpenCV's layout).
const HIST_LEN: usize = (GRID + 2) * (GRID + 2) * (CELL_BINS + 2);

/// Reusable per-sample buffers of [`describe`] and the orientation histogram.
#[derive(Clone, Debug, Default)]
pub struct GradientSamples {
    /// Horizontal gradient `I(x+1) − I(x−1)`.
    pub dx: Vec<f32>,
    /// Vertical gradient `I(y−1) − I(y+1)` (up positive).
    pub dy: Vec<f32>,
    /// Gaussian weight's exponent; [`GradientSamples::weigh`] turns it into `magnitude · weight`.
    pub weight: Vec<f32>,
    /// Gradient direction, degrees in `[0, 360)`, after [`GradientSamples::weigh`].
    pub angle: Vec<f32>,
    /// Row and column bins of the descriptor grid (unused by the orientation histogram).
    pub rbin: Vec<f32>,
    /// See `rbin`.
    pub cbin: Vec<f32>,
}

impl GradientSamples {
    /// Empties the buffers, keeping their allocations.
    pub fn clear(&mut self) {
        for v in [
            &mut self.dx,
            &mut self.dy,
            &mut self.weight,
            &mut self.angle,
            &mut self.rbin,
            &mut self.cbin,
        ] {
            v.clear();
        }
    }

    /// Directions and weighted magnitudes of all samples, in one vectorisable pass.
    pub fn weigh(&mut self) {
        self.angle.resize(self.dx.len(), 0.0);
        for (((a, w), &dx), &dy) in self
            .angle
            .iter_mut()
            .zip(self.weight.iter_mut())
            .zip(&self.dx)
            .zip(&self.dy)
        {
            *a = atan2_degrees(dy, dx);
            *w = (dx * dx + dy * dy).sqrt() * exp_nonpositive(*w);
        }
    }
}

/// The descriptor of a keypoint at sub-pixel `(x, y)` of the Gaussian level `image`, of scale
/// `scale` (level pixels) and OpenCV angle `angle` (degrees).
pub fn describe(
    image: &GrayImage,
    x: f32,
    y: f32,
    scale: f32,
    angle: f32,
    samples: &mut GradientSamples,
) -> Descriptor {
    let d = GRID as f32;
    // The histogram angle is 360° − the reported angle.
    let mut orientation = 360.0 - angle;
    if (orientation - 360.0).abs() < f32::EPSILON * 360.0 {
        orientation = 0.0;
    }
    let (pc, pr) = (x.round() as isize, y.round() as isize);
    let (sin_t, cos_t) = orientation.to_radians().sin_cos();
    let exp_scale = -1.0 / (d * d * 0.5);
    let cell_width = CELL_WIDTH_FACTOR * scale;
    let (w, h) = (image.width() as isize, image.height() as isize);
    let radius = (cell_width * std::f32::consts::SQRT_2 * (d + 1.0) * 0.5).round() as isize;
    let radius = radius.min(((w * w + h * h) as f64).sqrt() as isize);
    let (cos_t, sin_t) = (cos_t / cell_width, sin_t / cell_width);
    let half = d / 2.0 - 0.5;

    samples.clear();
    // Columns inside the image, as offsets from the keypoint.
    let (j_min, j_max) = ((-radius).max(1 - pc), radius.min(w - 2 - pc));
    for i in -radius..=radius {
        let r = pr + i;
        if r <= 0 || r >= h - 1 {
            continue;
        }
        let (above, row, below) = (
            image.row(r as usize - 1),
            image.row(r as usize),
            image.row(r as usize + 1),
        );
        // The offsets j whose rotated bins can fall inside the grid (a superset, one wider on
        // each side; the exact test follows), so most of the square window is not visited.
        let (lo, hi) = grid_span(i as f32, cos_t, sin_t, half, d);
        for j in j_min.max(lo)..=j_max.min(hi) {
            let c = pc + j;
            let c_rot = j as f32 * cos_t - i as f32 * sin_t;
            let r_rot = j as f32 * sin_t + i as f32 * cos_t;
            let rbin = r_rot + half;
            let cbin = c_rot + half;
            if !(rbin > -1.0 && rbin < d && cbin > -1.0 && cbin < d) {
                continue;
            }
            let c = c as usize;
            samples.dx.push(row[c + 1] - row[c - 1]);
            samples.dy.push(above[c] - below[c]);
            samples
                .weight
                .push((c_rot * c_rot + r_rot * r_rot) * exp_scale);
            samples.rbin.push(rbin);
            samples.cbin.push(cbin);
        }
    }
    samples.weigh();
    let bins_per_degree = CELL_BINS as f32 / 360.0;
    let mut hist = [0.0f32; HIST_LEN];
    for k in 0..samples.dx.len() {
        let obin = (samples.angle[k] - orientation) * bins_per_degree;
        spread(
            &mut hist,
            samples.rbin[k],
            samples.cbin[k],
            obin,
            samples.weight[k],
        );
    }
    finish(&hist)
}

/// The integer offsets `j` for which `rbin = j sin + i cos + half` and
/// `cbin = j cos − i sin + half` can both lie in `(−1, d)` (widened by one on each side).
fn grid_span(i: f32, cos_t: f32, sin_t: f32, half: f32, d: f32) -> (isize, isize) {
    let (mut lo, mut hi) = (f32::NEG_INFINITY, f32::INFINITY);
    for (slope, offset) in [(sin_t, i * cos_t + half), (cos_t, -i * sin_t + half)] {
        if slope.abs() < 1e-12 {
            if !(offset > -1.0 && offset < d) {
                return (1, 0);
            }
            continue;
        }
        let (a, b) = ((-1.0 - offset) / slope, (d - offset) / slope);
        lo = lo.max(a.min(b));
        hi = hi.min(a.max(b));
    }
    if lo > hi {
        return (1, 0);
    }
    (lo.floor() as isize - 1, hi.ceil() as isize + 1)
}

/// Adds `magnitude` to the eight histogram bins around `(rbin, cbin, obin)` with trilinear
/// weights.
#[inline]
fn spread(hist: &mut [f32; HIST_LEN], rbin: f32, cbin: f32, obin: f32, magnitude: f32) {
    let n = CELL_BINS as isize;
    let (r0, c0, mut o0) = (floor(rbin), floor(cbin), floor(obin));
    let (fr, fc, fo) = (rbin - r0 as f32, cbin - c0 as f32, obin - o0 as f32);
    if o0 < 0 {
        o0 += n;
    }
    if o0 >= n {
        o0 -= n;
    }
    let row_stride = (GRID + 2) * (CELL_BINS + 2);
    let cell_stride = CELL_BINS + 2;
    let base = ((r0 + 1) as usize) * row_stride + ((c0 + 1) as usize) * cell_stride + o0 as usize;
    let v_r1 = magnitude * fr;
    let v_r0 = magnitude - v_r1;
    for (dr, v_r) in [(0, v_r0), (1, v_r1)] {
        let v_c1 = v_r * fc;
        for (dc, v_c) in [(0, v_r - v_c1), (1, v_c1)] {
            let v_o1 = v_c * fo;
            let at = base + dr * row_stride + dc * cell_stride;
            hist[at] += v_c - v_o1;
            hist[at + 1] += v_o1;
        }
    }
}

/// `⌊v⌋` for |v| < 2³¹, exactly (a shifted truncation can round up at `d − ε`), without a
/// libm call.
#[inline(always)]
fn floor(v: f32) -> isize {
    let t = v as isize;
    if (t as f32) > v {
        t - 1
    } else {
        t
    }
}

/// Wraps the orientation margin, normalises, clips at [`CLIP`], renormalises and converts to
/// bytes.
fn finish(hist: &[f32; HIST_LEN]) -> Descriptor {
    let n = CELL_BINS;
    let mut v = [0.0f32; DESCRIPTOR_LEN];
    for i in 0..GRID {
        for j in 0..GRID {
            let at = ((i + 1) * (GRID + 2) + (j + 1)) * (n + 2);
            let cell = &mut v[(i * GRID + j) * n..(i * GRID + j + 1) * n];
            cell.copy_from_slice(&hist[at..at + n]);
            cell[0] += hist[at + n];
            cell[1] += hist[at + n + 1];
        }
    }
    let norm = v.iter().map(|x| x * x).sum::<f32>().sqrt();
    let clip = norm * CLIP;
    let mut norm2 = 0.0f32;
    for x in v.iter_mut() {
        *x = x.min(clip);
        norm2 += *x * *x;
    }
    let scale = BYTE_SCALE / norm2.sqrt().max(f32::EPSILON);
    v.map(|x| (x * scale).round().clamp(0.0, 255.0) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn textured(w: usize, h: usize) -> GrayImage {
        let data = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x as f32, y as f32)))
            .map(|(x, y)| {
                128.0
                    + 40.0 * (0.31 * x + 0.17 * y).sin()
                    + 30.0 * (0.23 * y - 0.11 * x).cos()
                    + 20.0 * (0.05 * x * y / 10.0).sin()
            })
            .collect();
        GrayImage::from_vec(w, h, data).unwrap()
    }

    fn distance(a: &Descriptor, b: &Descriptor) -> f32 {
        a.iter()
            .zip(b)
            .map(|(&x, &y)| (f32::from(x) - f32::from(y)).powi(2))
            .sum::<f32>()
            .sqrt()
    }

    #[test]
    fn floor_is_exact_next_to_the_grid_edge() {
        // 3.9999998 + 1 rounds to 5.0 in f32: a shifted truncation would give 4 here.
        assert_eq!(floor(3.999_999_8), 3);
        assert_eq!(floor(-0.5), -1);
        assert_eq!(floor(-1.0), -1);
        assert_eq!(floor(2.0), 2);
        let mut hist = [0.0f32; HIST_LEN];
        spread(&mut hist, 3.999_999_8, 3.999_999_8, 7.999_999, 1.0);
        assert!((hist.iter().sum::<f32>() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn bytes_are_a_clipped_unit_vector() {
        let d = describe(
            &textured(64, 64),
            32.0,
            32.0,
            2.0,
            30.0,
            &mut GradientSamples::default(),
        );
        let norm = d.iter().map(|&x| f32::from(x).powi(2)).sum::<f32>().sqrt();
        assert!((norm - 512.0).abs() < 8.0, "norm {norm}");
    }

    #[test]
    fn descriptor_is_invariant_to_90_degree_rotation() {
        // Rotating the image by 90° clockwise on screen (x' = h−1−y, y' = x) adds 90° to
        // OpenCV's angle.
        let (w, h) = (64, 64);
        let img = textured(w, h);
        let rotated: Vec<f32> = (0..w)
            .flat_map(|yr| (0..h).map(move |xr| (xr, yr)))
            .map(|(xr, yr)| img.at(yr, h - 1 - xr))
            .collect();
        let rotated = GrayImage::from_vec(h, w, rotated).unwrap();
        let (x, y, angle) = (30.0, 33.0, 40.0);
        let s = &mut GradientSamples::default();
        let a = describe(&img, x, y, 2.5, angle, s);
        let b = describe(&rotated, (h - 1) as f32 - y, x, 2.5, angle + 90.0, s);
        let other = describe(&img, 20.0, 40.0, 2.5, angle, s);
        let same = distance(&a, &b);
        assert!(same < 0.05 * 512.0, "distance {same}");
        assert!(distance(&a, &other) > 4.0 * same.max(1.0));
    }

    #[test]
    fn descriptor_is_invariant_to_affine_brightness() {
        let img = textured(64, 64);
        let brighter =
            GrayImage::from_vec(64, 64, img.data().iter().map(|v| 0.6 * v + 50.0).collect())
                .unwrap();
        let s = &mut GradientSamples::default();
        let a = describe(&img, 31.0, 30.0, 2.0, 10.0, s);
        let b = describe(&brighter, 31.0, 30.0, 2.0, 10.0, s);
        assert!(distance(&a, &b) <= 3.0, "distance {}", distance(&a, &b));
    }
}
