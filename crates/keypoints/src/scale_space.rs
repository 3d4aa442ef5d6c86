//! The Gaussian scale space and its differences of Gaussians (Eq. (3.1)), laid out as Lowe
//! and OpenCV do: octaves of `s + 3` Gaussian levels `σ_i = σ₀ · 2^{i/s}`, each octave
//! starting from the level `s` of the one before taken at every second pixel, and `s + 2`
//! difference images per octave.

use crate::gaussian_blur::{gaussian_blur, BlurScratch, GaussianKernel};
use crate::GrayImage;

/// Blur assumed already present in a camera image, pixels (Lowe's 0.5).
pub const INPUT_BLUR: f64 = 0.5;

/// The octave count is `round(log₂(min side) − 2)` of the (possibly upsampled) base image, so
/// the smallest octave is 3–6 pixels across. (OpenCV adds one more octave when it upsamples;
/// it is smaller than the detection border, so no keypoint can come from it.)
const SMALLEST_OCTAVE_LOG2: f64 = 2.0;

/// Geometry of a scale space: how many layers per octave, the base σ, and whether the input
/// was upsampled by 2 first (octave index −1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScaleSpaceLayout {
    /// `s`, intervals per octave (OpenCV's `nOctaveLayers`, 3).
    pub layers: usize,
    /// `σ₀` of the first level of every octave, in that octave's pixels (1.6).
    pub sigma: f64,
    /// Whether octave 0 is the input upsampled by 2 (Lowe's "−1" octave).
    pub upsample: bool,
}

/// One octave: `layers + 3` Gaussian levels and `layers + 2` differences.
#[derive(Clone, Debug, Default)]
pub struct Octave {
    /// `L(x, σ₀ 2^{i/s})`, i = 0 … s + 2.
    pub gaussians: Vec<GrayImage>,
    /// `D_i = L_{i+1} − L_i`, i = 0 … s + 1.
    pub dogs: Vec<GrayImage>,
}

/// The scale space of one image; buffers are kept between images of the same size.
#[derive(Clone, Debug, Default)]
pub struct ScaleSpace {
    /// The octaves, finest first.
    pub octaves: Vec<Octave>,
    /// Octaves in use (the vector may hold more from a larger image).
    pub octave_count: usize,
    scratch: BlurScratch,
    base: GrayImage,
}

impl ScaleSpace {
    /// Builds the scale space of `image` (intensities 0–255).
    pub fn build(&mut self, image: &GrayImage, layout: &ScaleSpaceLayout) {
        let s = layout.layers;
        let (base_w, base_h) = if layout.upsample {
            (2 * image.width(), 2 * image.height())
        } else {
            (image.width(), image.height())
        };
        let min_side = base_w.min(base_h).max(1) as f64;
        self.octave_count = ((min_side.log2() - SMALLEST_OCTAVE_LOG2).round()).max(1.0) as usize;
        if self.octaves.len() < self.octave_count {
            self.octaves.resize_with(self.octave_count, Octave::default);
        }
        for octave in &mut self.octaves {
            octave.gaussians.resize_with(s + 3, GrayImage::default);
            octave.dogs.resize_with(s + 2, GrayImage::default);
        }

        // The base: the input (upsampled) blurred from its assumed blur to σ₀.
        let present = if layout.upsample {
            upsample2(image, &mut self.base);
            2.0 * INPUT_BLUR
        } else {
            self.base.clone_from(image);
            INPUT_BLUR
        };
        let base_sigma = (layout.sigma * layout.sigma - present * present)
            .max(0.01)
            .sqrt();
        gaussian_blur(
            &self.base,
            &mut self.octaves[0].gaussians[0],
            &GaussianKernel::new(base_sigma),
            &mut self.scratch,
        );

        let kernels: Vec<GaussianKernel> = increment_sigmas(layout)
            .into_iter()
            .map(GaussianKernel::new)
            .collect();
        for o in 0..self.octave_count {
            if o > 0 {
                let (done, rest) = self.octaves.split_at_mut(o);
                downsample2(&done[o - 1].gaussians[s], &mut rest[0].gaussians[0]);
            }
            let octave = &mut self.octaves[o];
            for i in 1..s + 3 {
                let (lower, upper) = octave.gaussians.split_at_mut(i);
                gaussian_blur(
                    &lower[i - 1],
                    &mut upper[0],
                    &kernels[i - 1],
                    &mut self.scratch,
                );
            }
            for i in 0..s + 2 {
                let (a, b) = (&octave.gaussians[i], &octave.gaussians[i + 1]);
                let dog = &mut octave.dogs[i];
                dog.resize(a.width(), a.height());
                for ((d, &lo), &hi) in dog.data_mut().iter_mut().zip(a.data()).zip(b.data()) {
                    *d = hi - lo;
                }
            }
        }
    }
}

/// The blur that takes level `i − 1` to level `i` of an octave, `i = 1 … s + 2`:
/// `√(σ_i² − σ_{i−1}²)` with `σ_i = σ₀ 2^{i/s}`.
fn increment_sigmas(layout: &ScaleSpaceLayout) -> Vec<f64> {
    let k = 2f64.powf(1.0 / layout.layers as f64);
    (1..layout.layers + 3)
        .map(|i| {
            let previous = k.powi(i as i32 - 1) * layout.sigma;
            let total = previous * k;
            (total * total - previous * previous).sqrt()
        })
        .collect()
}

/// Where the upsampled image's pixel `X` lies in the input: `X / 2 − UPSAMPLE_SHIFT`.
pub const UPSAMPLE_SHIFT: f32 = 0.25;

/// `2×` bilinear upsampling on pixel areas (OpenCV's `resize(…, INTER_LINEAR)`): output pixel
/// `X` samples the input at `X / 2 − 1/4`, so every output pixel is the same 3:1 blend of two
/// neighbours and the blur is uniform (keeping the input on the even pixels instead makes
/// every second pixel sharper, and that pattern costs repeatability). Keypoint positions take
/// the quarter-pixel shift back ([`UPSAMPLE_SHIFT`]); OpenCV leaves it in its output. Edges
/// repeat.
fn upsample2(src: &GrayImage, dst: &mut GrayImage) {
    let (w, h) = (src.width(), src.height());
    let dw = 2 * w;
    dst.resize(dw, 2 * h);
    let out = dst.data_mut();
    let mut wide = vec![0.0f32; dw];
    let mut previous_wide = vec![0.0f32; dw];
    let widen = |row: &[f32], wide: &mut [f32]| {
        for x in 0..w {
            let (l, c, r) = (row[x.saturating_sub(1)], row[x], row[(x + 1).min(w - 1)]);
            wide[2 * x] = 0.75 * c + 0.25 * l;
            wide[2 * x + 1] = 0.75 * c + 0.25 * r;
        }
    };
    widen(src.row(0), &mut previous_wide);
    for y in 0..h {
        widen(src.row(y), &mut wide);
        let upper = std::mem::take(&mut previous_wide);
        let mut below = vec![0.0f32; dw];
        widen(src.row((y + 1).min(h - 1)), &mut below);
        let (even, odd) = out[2 * y * dw..(2 * y + 2) * dw].split_at_mut(dw);
        for x in 0..dw {
            even[x] = 0.75 * wide[x] + 0.25 * upper[x];
            odd[x] = 0.75 * wide[x] + 0.25 * below[x];
        }
        previous_wide = std::mem::take(&mut wide);
        wide = upper;
    }
}

/// Every second pixel (OpenCV's `INTER_NEAREST` halving).
fn downsample2(src: &GrayImage, dst: &mut GrayImage) {
    let (w, h) = (src.width() / 2, src.height() / 2);
    dst.resize(w.max(1), h.max(1));
    let dw = dst.width();
    let out = dst.data_mut();
    for y in 0..h.max(1) {
        let row = src.row((2 * y).min(src.height() - 1));
        for x in 0..dw {
            out[y * dw + x] = row[(2 * x).min(src.width() - 1)];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn increments_compose_to_the_level_sigmas() {
        let layout = ScaleSpaceLayout {
            layers: 3,
            sigma: 1.6,
            upsample: true,
        };
        let mut total = layout.sigma * layout.sigma;
        for (i, inc) in increment_sigmas(&layout).iter().enumerate() {
            total += inc * inc;
            let expected = layout.sigma * 2f64.powf((i + 1) as f64 / 3.0);
            assert!((total.sqrt() - expected).abs() < 1e-12);
        }
    }

    #[test]
    fn octave_layout_follows_opencv() {
        let layout = ScaleSpaceLayout {
            layers: 3,
            sigma: 1.6,
            upsample: true,
        };
        let image = GrayImage::new(64, 48);
        let mut space = ScaleSpace::default();
        space.build(&image, &layout);
        // round(log2(96) − 2) = round(4.58) = 5 octaves: 128×96, 64×48, 32×24, 16×12, 8×6.
        assert_eq!(space.octave_count, 5);
        let sizes: Vec<(usize, usize)> = space.octaves[..5]
            .iter()
            .map(|o| (o.gaussians[0].width(), o.gaussians[0].height()))
            .collect();
        assert_eq!(sizes, vec![(128, 96), (64, 48), (32, 24), (16, 12), (8, 6)]);
        assert!(space
            .octaves
            .iter()
            .all(|o| o.gaussians.len() == 6 && o.dogs.len() == 5));
    }

    #[test]
    fn upsampling_samples_the_input_a_quarter_pixel_back() {
        // A linear ramp v = 2x + 6y is reproduced exactly away from the edges, at
        // x = X/2 − 1/4, y = Y/2 − 1/4.
        let (w, h) = (5, 4);
        let data = (0..h)
            .flat_map(|y| (0..w).map(move |x| (2 * x + 6 * y) as f32))
            .collect();
        let src = GrayImage::from_vec(w, h, data).unwrap();
        let mut dst = GrayImage::default();
        upsample2(&src, &mut dst);
        assert_eq!((dst.width(), dst.height()), (10, 8));
        for yy in 1..7 {
            for xx in 1..9 {
                let (x, y) = (xx as f32 / 2.0 - 0.25, yy as f32 / 2.0 - 0.25);
                assert!(
                    (dst.at(xx, yy) - (2.0 * x + 6.0 * y)).abs() < 1e-5,
                    "({xx}, {yy})"
                );
            }
        }
        // Edges repeat: the first pixel is the input's first.
        assert_eq!(dst.at(0, 0), 0.0);
    }
}
