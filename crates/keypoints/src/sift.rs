//! The SIFT detector and descriptor: scale space → extrema → orientations → descriptors.

use crate::descriptor::{describe, GradientSamples};
use crate::extrema::{find_extrema, ExtremaOptions, Extremum};
use crate::orientation::{orientation_histogram, peak_angles};
use crate::scale_space::{ScaleSpace, ScaleSpaceLayout, UPSAMPLE_SHIFT};
use crate::{Features, GrayImage, Keypoint};

/// Options of [`Sift`]; the defaults are Lowe's and OpenCV's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SiftOptions {
    /// Intervals per octave, `s` (3).
    pub layers: usize,
    /// Contrast threshold on `|D(x̂)|`, intensities 0–1, applied as `|D| · s ≥ threshold`
    /// (OpenCV's 0.04).
    pub contrast_threshold: f32,
    /// Edge threshold `r`: candidates with principal-curvature ratio ≥ r are dropped (10).
    pub edge_threshold: f32,
    /// `σ₀` of the first level of an octave (1.6).
    pub sigma: f64,
    /// Double the image first (Lowe's "−1" octave), for more and smaller keypoints (true).
    /// Off, the work drops about fourfold and the keypoints smaller than ~2.5 px go.
    pub upsample: bool,
    /// Keep at most this many keypoints, the strongest `response`s (None: all).
    pub max_keypoints: Option<usize>,
}

impl Default for SiftOptions {
    fn default() -> Self {
        SiftOptions {
            layers: 3,
            contrast_threshold: 0.04,
            edge_threshold: 10.0,
            sigma: 1.6,
            upsample: true,
            max_keypoints: None,
        }
    }
}

/// A SIFT detector and describer whose buffers are kept between images (one per thread;
/// frames of one size reuse every allocation).
#[derive(Clone, Debug, Default)]
pub struct Sift {
    options: SiftOptions,
    space: ScaleSpace,
    extrema: Vec<Extremum>,
    angles: Vec<f32>,
    samples: GradientSamples,
}

/// A keypoint before sorting, with where its descriptor is read.
#[derive(Clone, Copy)]
struct Located {
    keypoint: Keypoint,
    extremum: Extremum,
}

impl Sift {
    /// A detector with `options`.
    pub fn new(options: SiftOptions) -> Self {
        Sift {
            options,
            ..Default::default()
        }
    }

    /// The options.
    pub fn options(&self) -> &SiftOptions {
        &self.options
    }

    /// Keypoints and descriptors of `image` (intensities 0–255), sorted by position as
    /// OpenCV sorts them (x, then y, size, angle), exact duplicates removed.
    pub fn detect_and_compute(&mut self, image: &GrayImage) -> Features {
        self.detect_and_compute_where(image, |_| true)
    }

    /// [`Sift::detect_and_compute`] for the keypoints `keep` accepts, asked before the
    /// descriptors are computed (and before [`SiftOptions::max_keypoints`] applies): a region of
    /// interest that is not a rectangle costs no descriptors outside it.
    pub fn detect_and_compute_where(
        &mut self,
        image: &GrayImage,
        mut keep: impl FnMut(&Keypoint) -> bool,
    ) -> Features {
        let o = self.options;
        if image.width() == 0 || image.height() == 0 {
            return Features::default();
        }
        let layout = ScaleSpaceLayout {
            layers: o.layers,
            sigma: o.sigma,
            upsample: o.upsample,
        };
        self.space.build(image, &layout);
        let extrema_options = ExtremaOptions {
            layers: o.layers,
            contrast_threshold: o.contrast_threshold,
            edge_threshold: o.edge_threshold,
            sigma: o.sigma as f32,
        };
        find_extrema(&self.space, &extrema_options, &mut self.extrema);

        let first_octave: i32 = if o.upsample { -1 } else { 0 };
        let mut located = Vec::with_capacity(self.extrema.len() * 5 / 4);
        for e in &self.extrema {
            let level = &self.space.octaves[e.octave].gaussians[e.layer];
            let hist = orientation_histogram(level, e.column, e.row, e.scale, &mut self.samples);
            peak_angles(&hist, &mut self.angles);
            let to_input = 2f32.powi(e.octave as i32 + first_octave);
            let shift = if o.upsample { UPSAMPLE_SHIFT } else { 0.0 };
            let octave = ((e.octave as i32 + first_octave) & 0xff)
                | ((e.layer as i32) << 8)
                | ((((e.layer_offset + 0.5) * 255.0).round() as i32) << 16);
            for &angle in &self.angles {
                located.push(Located {
                    keypoint: Keypoint {
                        x: e.x * to_input - shift,
                        y: e.y * to_input - shift,
                        size: 2.0 * e.scale * to_input,
                        angle,
                        response: e.response,
                        octave,
                    },
                    extremum: *e,
                });
            }
        }
        located.sort_by(|a, b| {
            let (p, q) = (&a.keypoint, &b.keypoint);
            (p.x, p.y, p.size, p.angle)
                .partial_cmp(&(q.x, q.y, q.size, q.angle))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        located.dedup_by(|a, b| {
            let (p, q) = (&a.keypoint, &b.keypoint);
            (p.x, p.y, p.size, p.angle) == (q.x, q.y, q.size, q.angle)
        });
        located.retain(|l| keep(&l.keypoint));
        if let Some(limit) = o.max_keypoints {
            if located.len() > limit {
                located.sort_by(|a, b| b.keypoint.response.total_cmp(&a.keypoint.response));
                located.truncate(limit);
                located.sort_by(|a, b| {
                    let (p, q) = (&a.keypoint, &b.keypoint);
                    (p.x, p.y)
                        .partial_cmp(&(q.x, q.y))
                        .unwrap_or(std::cmp::Ordering::Equal)
                });
            }
        }

        let descriptors = located
            .iter()
            .map(|l| {
                let e = &l.extremum;
                let level = &self.space.octaves[e.octave].gaussians[e.layer];
                describe(
                    level,
                    e.x,
                    e.y,
                    e.scale,
                    l.keypoint.angle,
                    &mut self.samples,
                )
            })
            .collect();
        Features {
            keypoints: located.into_iter().map(|l| l.keypoint).collect(),
            descriptors,
        }
    }
}
