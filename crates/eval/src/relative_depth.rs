//! The benchmark's relative-depth setting ([`crate::NoiseModel::relative`]): each frame's
//! relative inverse depth aligned to the metric face as `visage run --depth MODEL.onnx` does
//! it — the morphable model fitted to the simulated tracker's landmarks, rendered into a depth
//! map, and a robust scale and shift in inverse depth ([`visage_depth::align`]) — before any
//! method sees it. The aligned maps are the "raw" input of every method, so the methods are
//! compared with the aligned raw depth.

use serde::Serialize;
use visage_camera::{DepthKind, DepthMap};
use visage_depth::{align, AlignMode, AlignmentOptions, FrameRegion, OutputKind, Prediction};
use visage_mesh::TriMesh;
use visage_morphable::{FaceFitter, FaceModel, FitOptions};
use visage_render::render_depth;

use crate::simulated_tracker::TrackedSequence;
use crate::synthesis::SyntheticSequence;
use crate::EvalError;

/// The alignments of a sequence's frames.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SequenceAlignment {
    /// Per frame: the RMS depth residual against the fitted model over the inliers, metres
    /// (`None`: the frame could not be aligned and has no depth).
    pub residual_m: Vec<Option<f64>>,
}

/// The alignment over the benchmark's sequences (`results.json`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AlignmentSummary {
    pub frames: usize,
    pub failed: usize,
    pub median_residual_mm: f64,
    pub p95_residual_mm: f64,
}

impl AlignmentSummary {
    /// The summary of `sequences`.
    pub fn of(sequences: &[SequenceAlignment]) -> AlignmentSummary {
        let all: Vec<Option<f64>> = sequences
            .iter()
            .flat_map(|s| s.residual_m.iter().copied())
            .collect();
        let mut ok: Vec<f64> = all.iter().flatten().map(|r| r * 1e3).collect();
        ok.sort_by(f64::total_cmp);
        let rank = |q: f64| {
            ok.get(((q * ok.len() as f64).ceil() as usize).clamp(1, ok.len().max(1)) - 1)
                .copied()
                .unwrap_or(f64::NAN)
        };
        AlignmentSummary {
            frames: all.len(),
            failed: all.iter().filter(|r| r.is_none()).count(),
            median_residual_mm: rank(0.5),
            p95_residual_mm: rank(0.95),
        }
    }
}

/// Replaces every frame of `frames` (relative inverse depth, 0 = none) by its metric depth
/// aligned to `model` fitted to `tracking`'s landmarks (frames that cannot be aligned become
/// empty).
///
/// # Errors
/// A failing render of the fitted model.
pub fn align_to_fitted_model(
    truth: &SyntheticSequence,
    tracking: &TrackedSequence,
    model: &FaceModel,
    max_depth_m: f64,
    frames: &mut [DepthMap],
) -> Result<SequenceAlignment, EvalError> {
    let k = &truth.k;
    let mut fitter = FaceFitter::new(model, FitOptions::exact_landmarks());
    let mut shape = Vec::new();
    let mut mesh = TriMesh::new(Vec::new(), model.triangles.clone());
    let options = AlignmentOptions::default();
    let mut out = SequenceAlignment::default();
    for (landmarks, frame) in tracking.landmarks_px.iter().zip(frames.iter_mut()) {
        let fit = fitter.fit(k, landmarks, None);
        model.shape(fitter.identity(), &fit.expression, &mut shape);
        mesh.vertices.clear();
        mesh.vertices
            .extend(shape.iter().map(|&p| fit.pose.apply(p)));
        let reference = render_depth(&mesh, k, None, DepthKind::Z)
            .map_err(|e| EvalError::Degenerate {
                seed: truth.seed,
                reason: format!("rendering the fitted model: cannot render the face depth: {e}"),
            })?
            .depth;
        let prediction = Prediction {
            region: FrameRegion::frame(frame.width, frame.height),
            width: frame.width,
            height: frame.height,
            values: frame
                .data
                .iter()
                .map(|&y| if y > 0.0 { y } else { f32::NAN })
                .collect(),
        };
        match align(
            &prediction,
            &reference,
            OutputKind::Inverse,
            1.0,
            AlignMode::Auto,
            &options,
        ) {
            Ok(a) => {
                *frame = prediction.depth_map(
                    frame.width,
                    frame.height,
                    DepthKind::Z,
                    max_depth_m,
                    |x| a.depth(x),
                );
                out.residual_m.push(Some(a.residual_m));
            }
            Err(_) => {
                *frame = DepthMap::empty(frame.width, frame.height, DepthKind::Z);
                out.residual_m.push(None);
            }
        }
    }
    Ok(out)
}
