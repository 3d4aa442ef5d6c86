//! Bringing a depth network's output to the metric face: per frame, a robust fit of a scale
//! and a shift in the output's own space — depth for depth-like outputs, inverse depth for
//! inverse depth and disparity — against a reference depth map (the fitted face model's
//! surface), outliers rejected.
//!
//! With `x` the output at a reference pixel and `z` the reference depth there, the fit is
//! `y ≈ a·x + b` with `y = z` (depth-like) or `y = 1/z` (inverse), least squares in `y`:
//! 1. RANSAC on pairs of samples (a fixed pseudo-random sequence, so a frame always gives the
//!    same fit) keeps the hypothesis with the most samples whose depth lands within
//!    [`AlignmentOptions::initial_threshold_m`];
//! 2. iteratively reweighted least squares with Tukey's biweight, its scale 1.4826 × the median
//!    absolute depth residual (never below [`AlignmentOptions::residual_floor_m`]);
//! 3. samples within 2.5 of those scales are the inliers; the residual reported is the RMS
//!    depth difference over them (metres).
//!
//! A metric output is used as it is (`none`) or with a scale only; its residual is measured
//! the same way.

use serde::Serialize;
use visage_camera::DepthMap;

use crate::network_config::{AlignMode, OutputKind};
use crate::Prediction;

/// Fit settings (defaults: up to 3,000 samples, 64 RANSAC hypotheses, 20 mm, a 1 mm floor,
/// at least 50 samples and inliers).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlignmentOptions {
    /// Reference pixels used at most (a regular grid over the valid ones).
    pub max_samples: usize,
    /// Fewest samples (and inliers) a fit needs.
    pub min_samples: usize,
    /// RANSAC hypotheses.
    pub hypotheses: usize,
    /// Depth difference within which a sample supports a RANSAC hypothesis, metres.
    pub initial_threshold_m: f64,
    /// Smallest residual scale of the reweighting, metres.
    pub residual_floor_m: f64,
}

impl Default for AlignmentOptions {
    fn default() -> Self {
        AlignmentOptions {
            max_samples: 3000,
            min_samples: 50,
            hypotheses: 64,
            initial_threshold_m: 0.02,
            residual_floor_m: 0.001,
        }
    }
}

/// A frame's alignment: `y = scale · value + shift` in the output's space.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Alignment {
    pub scale: f64,
    pub shift: f64,
    /// RMS depth difference from the reference over the inliers, metres.
    pub residual_m: f64,
    /// Samples that agree with the fit, and samples drawn.
    pub inliers: usize,
    pub samples: usize,
    /// Whether `y` is inverse depth.
    #[serde(skip)]
    pub inverse: bool,
}

impl Alignment {
    /// The metric depth (metres) of an output value; NaN or ≤ 0 where it gives none.
    #[inline]
    pub fn depth(&self, value: f64) -> f64 {
        let y = self.scale * value + self.shift;
        if self.inverse {
            1.0 / y
        } else {
            y
        }
    }
}

/// Why a frame could not be aligned.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AlignmentFailure {
    #[error("{found} reference pixels under the network's region (need {needed})")]
    TooFewSamples { found: usize, needed: usize },
    #[error("only {inliers} of {samples} samples agree with any scale and shift")]
    NoConsensus { inliers: usize, samples: usize },
    #[error(
        "the output falls where the face's depth rises (scale {scale:.3}): is the output kind \
         right (depth against inverse depth)?"
    )]
    Inverted { scale: f64 },
}

/// One sample: the output value (in the fit's units) and the reference depth.
#[derive(Clone, Copy, Debug)]
struct Sample {
    x: f64,
    z: f64,
}

/// Aligns `prediction` (values of `kind`; `metric_scale` turns a metric value into metres) to
/// `reference` (a depth map of the frame, metres, of the kind the output measures) with
/// `mode` ([`AlignMode::Auto`] as [`crate::NetworkConfig::alignment`] resolves it).
///
/// # Errors
/// Too few reference pixels under the region, no consensus, or a fit whose scale is not
/// positive (the output's kind is likely wrong).
pub fn align(
    prediction: &Prediction,
    reference: &DepthMap,
    kind: OutputKind,
    metric_scale: f64,
    mode: AlignMode,
    options: &AlignmentOptions,
) -> Result<Alignment, AlignmentFailure> {
    let inverse = kind.is_inverse();
    let unit = if kind == OutputKind::Metric {
        metric_scale
    } else {
        1.0
    };
    let samples = draw_samples(prediction, reference, unit, options.max_samples);
    if samples.len() < options.min_samples {
        return Err(AlignmentFailure::TooFewSamples {
            found: samples.len(),
            needed: options.min_samples,
        });
    }
    let mode = match (mode, kind) {
        (AlignMode::Auto, OutputKind::Metric) => AlignMode::None,
        (AlignMode::Auto, _) => AlignMode::ScaleShift,
        (m, _) => m,
    };
    let mut fit = Alignment {
        scale: 1.0,
        shift: 0.0,
        residual_m: 0.0,
        inliers: 0,
        samples: samples.len(),
        inverse,
    };
    let target = |s: &Sample| if inverse { 1.0 / s.z } else { s.z };
    if mode != AlignMode::None {
        let shift = mode == AlignMode::ScaleShift;
        let (a, b) = ransac(&samples, inverse, shift, options, &target);
        fit.scale = a;
        fit.shift = b;
        let mut residuals = vec![0.0; samples.len()];
        let mut weights = vec![1.0; samples.len()];
        for _ in 0..8 {
            let sigma = residual_scale(&fit, &samples, &mut residuals, options);
            let c = 4.685 * sigma;
            for (w, r) in weights.iter_mut().zip(&residuals) {
                let t = r / c;
                *w = if t.abs() < 1.0 {
                    (1.0 - t * t).powi(2)
                } else {
                    0.0
                };
            }
            let Some((a, b)) = weighted_line(&samples, &weights, shift, &target) else {
                break;
            };
            fit.scale = a;
            fit.shift = b;
        }
    }
    if !(fit.scale.is_finite() && fit.shift.is_finite()) || fit.scale <= 0.0 {
        return Err(AlignmentFailure::Inverted { scale: fit.scale });
    }
    let mut residuals = vec![0.0; samples.len()];
    let sigma = residual_scale(&fit, &samples, &mut residuals, options);
    let (mut sum, mut inliers) = (0.0, 0usize);
    for r in residuals.iter().filter(|r| r.abs() <= 2.5 * sigma) {
        sum += r * r;
        inliers += 1;
    }
    fit.inliers = inliers;
    fit.residual_m = (sum / inliers.max(1) as f64).sqrt();
    if inliers < options.min_samples {
        return Err(AlignmentFailure::NoConsensus {
            inliers,
            samples: samples.len(),
        });
    }
    // A metric output's own scale is folded in: `depth` takes raw values.
    fit.scale *= unit;
    Ok(fit)
}

/// Up to `max` (value × `unit`, reference depth) pairs on a regular grid over the valid
/// reference pixels the prediction covers.
fn draw_samples(
    prediction: &Prediction,
    reference: &DepthMap,
    unit: f64,
    max: usize,
) -> Vec<Sample> {
    let valid = reference.valid_count();
    let stride = ((valid as f64 / max.max(1) as f64).sqrt().ceil() as u32).max(1);
    let mut samples = Vec::with_capacity(max.min(valid));
    for v in (0..reference.height).step_by(stride as usize) {
        for u in (0..reference.width).step_by(stride as usize) {
            let z = reference.at(u, v);
            if !DepthMap::is_valid(z) {
                continue;
            }
            if let Some(x) = prediction.at(u as f64, v as f64) {
                if x.is_finite() {
                    samples.push(Sample {
                        x: x as f64 * unit,
                        z: z as f64,
                    });
                }
            }
        }
    }
    samples
}

/// Fills `residuals` (depth of the fit − reference, metres; infinite where the fit gives no
/// depth) and returns their robust scale: 1.4826 × the median absolute residual, at least
/// the floor.
fn residual_scale(
    fit: &Alignment,
    samples: &[Sample],
    residuals: &mut [f64],
    options: &AlignmentOptions,
) -> f64 {
    for (r, s) in residuals.iter_mut().zip(samples) {
        let z = fit.depth(s.x);
        *r = if z.is_finite() && z > 0.0 {
            z - s.z
        } else {
            f64::INFINITY
        };
    }
    let mut abs: Vec<f64> = residuals.iter().map(|r| r.abs()).collect();
    let mid = abs.len() / 2;
    let (_, &mut median, _) = abs.select_nth_unstable_by(mid, f64::total_cmp);
    (1.4826 * median).max(options.residual_floor_m)
}

/// The RANSAC hypothesis (scale, shift) with the most support.
fn ransac(
    samples: &[Sample],
    inverse: bool,
    shift: bool,
    options: &AlignmentOptions,
    target: &dyn Fn(&Sample) -> f64,
) -> (f64, f64) {
    let n = samples.len();
    // xorshift64: the same hypotheses every time.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % n as u64) as usize
    };
    let mut best = (1.0, 0.0, 0usize);
    let support = |a: f64, b: f64| {
        let fit = Alignment {
            scale: a,
            shift: b,
            residual_m: 0.0,
            inliers: 0,
            samples: 0,
            inverse,
        };
        samples
            .iter()
            .filter(|s| (fit.depth(s.x) - s.z).abs() < options.initial_threshold_m)
            .count()
    };
    for _ in 0..options.hypotheses {
        let (i, j) = (next(), next());
        let (p, q) = (&samples[i], &samples[j]);
        let (a, b) = if shift {
            let dx = q.x - p.x;
            if dx.abs() < 1e-12 {
                continue;
            }
            let a = (target(q) - target(p)) / dx;
            (a, target(p) - a * p.x)
        } else if p.x.abs() > 1e-12 {
            (target(p) / p.x, 0.0)
        } else {
            continue;
        };
        if !(a.is_finite() && b.is_finite()) || a <= 0.0 {
            continue;
        }
        let count = support(a, b);
        if count > best.2 {
            best = (a, b, count);
        }
    }
    if best.2 == 0 {
        // No hypothesis held: start from least squares on everything.
        let weights = vec![1.0; n];
        if let Some((a, b)) = weighted_line(samples, &weights, shift, target) {
            return (a, b);
        }
    }
    (best.0, best.1)
}

/// Weighted least squares `target ≈ a·x + b` (`b = 0` without `shift`); `None` when
/// degenerate.
fn weighted_line(
    samples: &[Sample],
    weights: &[f64],
    shift: bool,
    target: &dyn Fn(&Sample) -> f64,
) -> Option<(f64, f64)> {
    let (mut sw, mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (s, &w) in samples.iter().zip(weights) {
        let y = target(s);
        sw += w;
        sx += w * s.x;
        sy += w * y;
        sxx += w * s.x * s.x;
        sxy += w * s.x * y;
    }
    if sw <= 0.0 {
        return None;
    }
    if !shift {
        return (sxx > 0.0).then(|| (sxy / sxx, 0.0));
    }
    let det = sw * sxx - sx * sx;
    if det.abs() <= 1e-12 * sw * sxx.max(1e-300) {
        return None;
    }
    let a = (sw * sxy - sx * sy) / det;
    Some((a, (sy - a * sx) / sw))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::FrameRegion;
    use visage_camera::DepthKind;

    /// A 64×48 reference: a tilted plane at about 0.5 m over the middle, background around.
    fn reference() -> DepthMap {
        let mut d = DepthMap::empty(64, 48, DepthKind::Z);
        for v in 8..40 {
            for u in 10..54 {
                d.data[v * 64 + u] = 0.5 + 0.001 * u as f32 - 0.0005 * v as f32;
            }
        }
        d
    }

    /// The prediction whose value at each pixel is `f(reference)` (background: 0.01).
    fn prediction_of(reference: &DepthMap, f: impl Fn(f64) -> f64) -> Prediction {
        Prediction {
            region: FrameRegion::frame(reference.width, reference.height),
            width: reference.width,
            height: reference.height,
            values: reference
                .data
                .iter()
                .map(|&z| if z > 0.0 { f(z as f64) as f32 } else { 0.01 })
                .collect(),
        }
    }

    #[test]
    fn a_relative_inverse_depth_is_brought_back_to_metres() {
        let r = reference();
        // Inverse depth with an unknown scale and shift, as MiDaS gives it.
        let mut p = prediction_of(&r, |z| 3.0 / z + 7.0);
        // 10 % of the pixels are wild (a hand, a reflection).
        for (i, v) in p.values.iter_mut().enumerate() {
            if i % 10 == 3 {
                *v = 40.0;
            }
        }
        let fit = align(
            &p,
            &r,
            OutputKind::Inverse,
            1.0,
            AlignMode::Auto,
            &AlignmentOptions::default(),
        )
        .unwrap();
        assert!(fit.residual_m < 1e-5, "{fit:?}");
        assert!((fit.depth(3.0 / 0.55 + 7.0) - 0.55).abs() < 1e-5, "{fit:?}");
        assert!(fit.inliers < fit.samples && fit.inliers > fit.samples * 8 / 10);
    }

    #[test]
    fn relative_depth_aligns_in_depth_and_metric_depth_keeps_its_scale() {
        let r = reference();
        let p = prediction_of(&r, |z| 20.0 * z - 3.0);
        let fit = align(
            &p,
            &r,
            OutputKind::Relative,
            1.0,
            AlignMode::Auto,
            &AlignmentOptions::default(),
        )
        .unwrap();
        assert!(
            (fit.depth(20.0 * 0.52 - 3.0) - 0.52).abs() < 1e-6,
            "{fit:?}"
        );
        // Millimetres, 2 % too far: used as they are, the residual says by how much.
        let mm = prediction_of(&r, |z| 1020.0 * z);
        let fit = align(
            &mm,
            &r,
            OutputKind::Metric,
            0.001,
            AlignMode::Auto,
            &AlignmentOptions::default(),
        )
        .unwrap();
        assert!((fit.depth(510.0) - 0.51).abs() < 1e-9);
        assert!((fit.residual_m - 0.01).abs() < 0.001, "{fit:?}");
        let scaled = align(
            &mm,
            &r,
            OutputKind::Metric,
            0.001,
            AlignMode::Scale,
            &AlignmentOptions::default(),
        )
        .unwrap();
        assert!(scaled.residual_m < 1e-5 && (scaled.depth(510.0) - 0.5).abs() < 1e-5);
    }

    #[test]
    fn a_wrong_kind_or_an_empty_reference_is_a_failure_not_a_fit() {
        let r = reference();
        // Depth given, inverse depth announced: the fit's scale turns negative.
        let p = prediction_of(&r, |z| 20.0 * z);
        let e = align(
            &p,
            &r,
            OutputKind::Inverse,
            1.0,
            AlignMode::Auto,
            &AlignmentOptions::default(),
        )
        .unwrap_err();
        assert!(
            matches!(
                e,
                AlignmentFailure::Inverted { .. } | AlignmentFailure::NoConsensus { .. }
            ),
            "{e}"
        );
        let empty = DepthMap::empty(64, 48, DepthKind::Z);
        let e = align(
            &p,
            &empty,
            OutputKind::Inverse,
            1.0,
            AlignMode::Auto,
            &AlignmentOptions::default(),
        )
        .unwrap_err();
        assert!(matches!(
            e,
            AlignmentFailure::TooFewSamples { found: 0, .. }
        ));
    }
}
