//! The face-model fit against the generator's truth: on each synthetic sequence the fit sees
//! the simulated tracker's 468 noisy landmarks (nothing else) and is scored on what it claims
//! to recover: the expression weights and this face's identity.
//!
//! The benchmark's tracker puts each landmark on the ICT surface (its material point), so the
//! fitted model here is the one `visage model build` makes from the same ICT folder, with the
//! per-landmark offsets — MediaPipe's own notion of a landmark, which synthetic landmarks do
//! not have — set to 0. The gap between the two notions is measured on real frames instead.
//! Landmarks cannot see a uniform scale of the face about the camera (a larger face further
//! away projects the same), so the identity's shape error is taken after the best scale, and
//! the scale error reported beside it.

use std::time::Instant;

use serde::Serialize;
use visage_morphable::fit::rms_after_scale;
use visage_morphable::{FaceFitter, FaceModel, FitOptions, IctModel, Region};

use crate::simulated_tracker::TrackedSequence;
use crate::synthesis::SyntheticSequence;

/// Frames the identity gets before expressions are scored (at most half the sequence).
pub const SETTLE_FRAMES: usize = 60;

/// One sequence's scores.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ModelFitScore {
    /// Mean |fitted − true| expression weight over the expressions and the frames after
    /// [`SETTLE_FRAMES`] (or the first half of a shorter sequence), the eye-look shapes left
    /// out: they are gaze, which the fit takes from the irises, and the simulated tracker has
    /// none.
    pub expression_mae: f64,
    /// The same for weights that are all 0 (the simplest guess, for scale).
    pub zero_guess_mae: f64,
    /// RMS distance (mm) of the fitted neutral face from the true one over the face region,
    /// after the best uniform scale, at the end of the sequence.
    pub identity_rmse_mm: f64,
    /// |fitted scale / true scale − 1| of that neutral face.
    pub identity_scale_error: f64,
    /// Mean landmark reprojection error (px) after [`SETTLE_FRAMES`].
    pub reprojection_px: f64,
    /// Fit time per frame (ms).
    pub ms_per_frame: f64,
}

/// The compact model of `ict` for the benchmark's tracker (landmarks on the surface).
pub fn benchmark_face_model(
    ict: &IctModel,
    correspondence: &visage_morphable::CanonicalCorrespondence,
) -> Result<FaceModel, visage_morphable::MorphableError> {
    let mut model = FaceModel::from_ict(ict, correspondence)?;
    model
        .landmark_offsets
        .iter_mut()
        .for_each(|o| *o = [0.0; 3]);
    // The neutral is moved to the calibrated identity; the truth is relative to the ICT
    // neutral, so the shapes are compared as shapes (see `score`).
    Ok(model)
}

/// Fits `model` to `tracking`'s landmarks of `truth` frame by frame and scores it.
pub fn score(
    ict: &IctModel,
    model: &FaceModel,
    truth: &SyntheticSequence,
    tracking: &TrackedSequence,
) -> ModelFitScore {
    let mut fitter = FaceFitter::new(model, FitOptions::exact_landmarks());
    // The fitted expression j is the truth's expression `truth_index[j]`.
    let truth_index: Vec<Option<usize>> = model
        .expression_names
        .iter()
        .map(|name| ict.expression_index(name))
        .collect();
    let (mut abs_error, mut count, mut reprojection, mut scored) = (0.0, 0usize, 0.0, 0usize);
    let mut zero_error = 0.0;
    let settle = SETTLE_FRAMES.min(truth.frames.len() / 2);
    let start = Instant::now();
    for (k, (landmarks, frame)) in tracking.landmarks_px.iter().zip(&truth.frames).enumerate() {
        let fit = fitter.fit(&truth.k, landmarks, None);
        if k < settle {
            continue;
        }
        for ((w, t), name) in fit
            .expression
            .iter()
            .zip(&truth_index)
            .zip(&model.expression_names)
        {
            if name.starts_with("eyeLook") {
                continue;
            }
            let true_w = t.map_or(0.0, |t| frame.expression[t]);
            abs_error += (w - true_w).abs();
            zero_error += true_w.abs();
            count += 1;
        }
        reprojection += fit.mean_error_px;
        scored += 1;
    }
    let ms_per_frame = start.elapsed().as_secs_f64() * 1e3 / truth.frames.len().max(1) as f64;
    let face = Region::Face.range();
    let mut fitted = Vec::new();
    model.shape(fitter.identity(), &[], &mut fitted);
    let mut true_shape = Vec::new();
    let zeros = vec![0.0; ict.expression_modes.len()];
    if ict.shape(&truth.identity, &zeros, &mut true_shape).is_err() {
        true_shape = ict.neutral.clone();
    }
    let (rmse, scale) = rms_after_scale(&fitted, &true_shape[face]);
    ModelFitScore {
        expression_mae: abs_error / count.max(1) as f64,
        zero_guess_mae: zero_error / count.max(1) as f64,
        identity_rmse_mm: rmse * 1e3,
        identity_scale_error: (scale - 1.0).abs(),
        reprojection_px: reprojection / scored.max(1) as f64,
        ms_per_frame,
    }
}

/// Scores over sequences, averaged.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ModelFitSummary {
    pub sequences: usize,
    pub mean: ModelFitScore,
}

impl ModelFitSummary {
    /// The mean of `scores`.
    pub fn of(scores: &[ModelFitScore]) -> ModelFitSummary {
        let n = scores.len().max(1) as f64;
        let mean = |f: &dyn Fn(&ModelFitScore) -> f64| scores.iter().map(f).sum::<f64>() / n;
        ModelFitSummary {
            sequences: scores.len(),
            mean: ModelFitScore {
                expression_mae: mean(&|s| s.expression_mae),
                zero_guess_mae: mean(&|s| s.zero_guess_mae),
                identity_rmse_mm: mean(&|s| s.identity_rmse_mm),
                identity_scale_error: mean(&|s| s.identity_scale_error),
                reprojection_px: mean(&|s| s.reprojection_px),
                ms_per_frame: mean(&|s| s.ms_per_frame),
            },
        }
    }
}
