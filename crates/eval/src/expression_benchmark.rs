//! The expression benchmark from pixels (`visage eval expressions`): a recorded ARKit take
//! replayed on a rendered ICT-FaceKit head ([`crate::Replay`]), run through the pipeline
//! exactly as `visage run` runs a video (the `visage` facade's `Reconstructor::run`, its
//! defaults: detector, landmarks and their smoother, irises, the model fit, the rest pose),
//! and the 52 weights it gives (what `blendshapes.csv` gets) scored against the played ones
//! ([`crate::expression_scores`]), with the head's rotation and the fitted identity.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use visage::run_folder::read_live_link_csv;
use visage::{BlendshapeFrame, Error, FrameSink, Reconstructor};
use visage_morphable::{IctModel, Region};
use visage_rig::{live_link_rotation, ARKIT_BLENDSHAPES, ARKIT_BLENDSHAPE_COUNT};

use crate::error::ClipRunError;
use crate::expression_replay::{Replay, ReplayOptions};
use crate::expression_scores::{
    aligned_rms, from_rest, mae, pearson, quantile_sorted, rest_frames, rigid_leak, rms,
    rotation_angle_deg, BlinkCounts,
};
use crate::head_render::HeadRender;
use crate::EvalError;

/// The quantile of the rigid leak reported.
pub const LEAK_QUANTILE: f64 = 0.99;

/// How the pipeline is run and what is kept besides the scores.
#[derive(Clone, Debug, Default)]
pub struct ExpressionOptions {
    pub replay: ReplayOptions,
    /// MediaPipe's model files (`None`: where `visage run` looks).
    pub models: Option<PathBuf>,
    /// Write this many frames of each take, evenly spread, as PNG into `frames_dir`.
    pub save_frames: usize,
    pub frames_dir: Option<PathBuf>,
    /// Score the weights as the fit reads them, with what the head's turn adds left on
    /// (`visage_rig::PoseLeak` off, and `visage_rig::MouthLeak` with it; the pose leak's
    /// table is learned from such runs).
    pub keep_pose_leak: bool,
    /// Score the weights with what the mouth's shapes add to the upper face's left on
    /// (`visage_rig::MouthLeak` off; its table is learned from such runs).
    pub keep_mouth_leak: bool,
}

/// One shape's scores over a take (or all takes).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ShapeScore {
    /// Mean absolute error, weight units.
    pub mae: Option<f64>,
    /// The same against the played weight relative to the take's resting value
    /// ([`crate::expression_scores::from_rest`]): what a reading relative to the person's rest
    /// — the pipeline's — can return.
    pub mae_from_rest: Option<f64>,
    /// The MAE of a perfect reading relative to the person's rest: the played weight relative
    /// to the take's resting value against the played weight. No reading relative to the rest
    /// (the pipeline's, Live Link Face's once calibrated) can score a lower `mae`.
    pub mae_floor: Option<f64>,
    /// Pearson's r of read against played (`None` where either is constant).
    pub r: Option<f64>,
    /// The 99th percentile of this weight's change over the frames at rest
    /// ([`crate::expression_scores::rigid_leak`]; over all takes: the largest take's).
    pub leak_p99: Option<f64>,
}

/// The summary figures of a take or of all takes.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ExpressionSummary {
    /// Mean over the 51 shapes with an ICT counterpart (not `tongueOut`) of each shape's MAE,
    /// over the frames with a face.
    pub mae: Option<f64>,
    /// The same against the played weights relative to each take's resting values
    /// ([`ShapeScore::mae_from_rest`]).
    pub mae_from_rest: Option<f64>,
    /// The lowest `mae` a reading relative to the person's rest can score
    /// ([`ShapeScore::mae_floor`]).
    pub mae_floor: Option<f64>,
    /// Blinks caught: runs of frames with a played `eyeBlink*` ≥ 0.8 in which the read one
    /// reaches 0.6 (both eyes).
    pub blink_hit_rate: Option<f64>,
    /// Frames with a played `eyeBlink*` < 0.2 whose read one is ≥ 0.6, over those frames.
    pub false_closure_rate: Option<f64>,
    /// The counts behind the two rates.
    pub blinks: BlinkCounts,
    /// The 99th percentile, over every weight and every frame at rest, of the read weight's
    /// change ([`crate::expression_scores::rigid_leak`]).
    pub rigid_leak_p99: Option<f64>,
    /// The weight whose own 99th percentile of change is the largest, and that value.
    pub rigid_leak_worst: Option<(String, f64)>,
    /// RMS over frames of the geodesic angle between the played and the read head rotation
    /// (both in the face frame relative to facing the camera; no offset removed), degrees.
    pub head_rotation_rmse_deg: Option<f64>,
    /// RMS of the read minus the played Live Link Face `[yaw, pitch, roll]`, degrees: where
    /// the rotation error lies.
    pub head_angle_rmse_deg: Option<[f64; 3]>,
    /// RMS distance between the fitted and the rendered neutral face over the narrow face
    /// region (ICT vertices 0–6705) after a rigid alignment without scale, mm.
    pub identity_error_mm: Option<f64>,
    /// Frames played, frames at rest, frames the pipeline found a face in (and so gave
    /// weights for).
    pub frames: usize,
    pub rest_frames: usize,
    pub frames_with_face: usize,
    /// Wall time per frame, rendering included (the render runs on the pipeline's decoding
    /// thread), milliseconds.
    pub ms_per_frame: f64,
}

/// One take's results.
#[derive(Clone, Debug, serde::Serialize)]
pub struct TakeResult {
    pub take: String,
    pub summary: ExpressionSummary,
    /// Per ARKit shape, by name.
    pub shapes: BTreeMap<String, ShapeScore>,
    /// The played and read curves of the frames with a face (for the plots; not in the JSON).
    #[serde(skip)]
    pub curves: Curves,
}

/// Played and read weights and head angles, frame by frame, of the frames with a face.
#[derive(Clone, Debug, Default)]
pub struct Curves {
    pub time_s: Vec<f64>,
    pub played: Vec<[f32; ARKIT_BLENDSHAPE_COUNT]>,
    /// The played weights relative to the take's resting values (`from_rest`).
    pub played_from_rest: Vec<[f32; ARKIT_BLENDSHAPE_COUNT]>,
    pub read: Vec<[f32; ARKIT_BLENDSHAPE_COUNT]>,
    /// Live Link Face's head yaw, pitch and roll (radians), played and read.
    pub played_head: Vec<[f64; 3]>,
    pub read_head: Vec<[f64; 3]>,
}

/// Every take's results and the summary over all of them.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ExpressionResults {
    pub summary: ExpressionSummary,
    /// Per ARKit shape over all takes' frames.
    pub shapes: BTreeMap<String, ShapeScore>,
    pub takes: Vec<TakeResult>,
    pub options: ReplayOptions,
    /// The camera the frames were rendered with and the pipeline was given.
    pub intrinsics: visage::Intrinsics,
}

/// What the pipeline gave for each frame: its weights and rotations (only frames with a
/// face get them).
#[derive(Default)]
struct Collected {
    weights: BTreeMap<usize, BlendshapeFrame>,
}

impl FrameSink for Collected {
    fn blendshapes(&mut self, frame: &BlendshapeFrame) -> Result<(), Error> {
        self.weights.insert(frame.index, frame.clone());
        Ok(())
    }
}

/// Runs every take in `takes` through `render` and the pipeline and scores it.
///
/// # Errors
/// A take that cannot be read or planned, a pipeline that cannot be set up or stops.
pub fn evaluate_expressions(
    takes: &[PathBuf],
    render: &Arc<HeadRender>,
    options: &ExpressionOptions,
) -> Result<ExpressionResults, EvalError> {
    let results = takes
        .iter()
        .map(|path| evaluate_take(path, render, options))
        .collect::<Result<Vec<_>, _>>()?;
    let mut all = Curves::default();
    for t in &results {
        all.time_s.extend(&t.curves.time_s);
        all.played.extend(&t.curves.played);
        all.played_from_rest.extend(&t.curves.played_from_rest);
        all.read.extend(&t.curves.read);
        all.played_head.extend(&t.curves.played_head);
        all.read_head.extend(&t.curves.read_head);
    }
    let frames: usize = results.iter().map(|t| t.summary.frames).sum();
    let weighted = |f: fn(&ExpressionSummary) -> Option<f64>| {
        let (mut sum, mut n) = (0.0, 0.0);
        for t in &results {
            if let Some(v) = f(&t.summary) {
                sum += v * t.summary.frames as f64;
                n += t.summary.frames as f64;
            }
        }
        (n > 0.0).then(|| sum / n)
    };
    let blinks = results.iter().fold(BlinkCounts::default(), |acc, t| {
        acc + blink_counts(&t.curves)
    });
    let mut shapes = shape_scores(&all, None);
    for (name, score) in &mut shapes {
        score.leak_p99 = results
            .iter()
            .filter_map(|t| t.shapes[name].leak_p99)
            .reduce(f64::max);
    }
    let summary = ExpressionSummary {
        mae: mean_mae(&shapes, |s| s.mae),
        mae_from_rest: mean_mae(&shapes, |s| s.mae_from_rest),
        mae_floor: mean_mae(&shapes, |s| s.mae_floor),
        blink_hit_rate: blinks.hit_rate(),
        false_closure_rate: blinks.false_closure_rate(),
        blinks,
        rigid_leak_p99: results
            .iter()
            .filter_map(|t| t.summary.rigid_leak_p99)
            .reduce(f64::max),
        rigid_leak_worst: results
            .iter()
            .filter_map(|t| t.summary.rigid_leak_worst.clone())
            .reduce(|a, b| if b.1 > a.1 { b } else { a }),
        head_rotation_rmse_deg: {
            // RMS over all frames: weight each take's mean square by its frames.
            let (mut sum, mut n) = (0.0, 0.0);
            for t in &results {
                if let Some(v) = t.summary.head_rotation_rmse_deg {
                    sum += v * v * t.summary.frames_with_face as f64;
                    n += t.summary.frames_with_face as f64;
                }
            }
            (n > 0.0).then(|| (sum / n).sqrt())
        },
        head_angle_rmse_deg: {
            let (mut sum, mut n) = ([0.0; 3], 0.0);
            for t in &results {
                if let Some(v) = t.summary.head_angle_rmse_deg {
                    let w = t.summary.frames_with_face as f64;
                    for c in 0..3 {
                        sum[c] += v[c] * v[c] * w;
                    }
                    n += w;
                }
            }
            (n > 0.0).then(|| sum.map(|s| (s / n).sqrt()))
        },
        identity_error_mm: weighted(|s| s.identity_error_mm),
        frames,
        rest_frames: results.iter().map(|t| t.summary.rest_frames).sum(),
        frames_with_face: results.iter().map(|t| t.summary.frames_with_face).sum(),
        ms_per_frame: weighted(|s| Some(s.ms_per_frame)).unwrap_or(0.0),
    };
    Ok(ExpressionResults {
        summary,
        shapes,
        takes: results,
        options: options.replay.clone(),
        intrinsics: *render.intrinsics(),
    })
}

/// Replays one take and scores what the pipeline read.
fn evaluate_take(
    path: &Path,
    render: &Arc<HeadRender>,
    options: &ExpressionOptions,
) -> Result<TakeResult, EvalError> {
    let take = read_live_link_csv(path).map_err(visage::Error::from)?;
    let model = render.model();
    let replay = Replay::plan(path, &take, &options.replay, model.identity_modes.len())?;
    let n = replay.frames.len();
    let save: Vec<usize> = if options.save_frames == 0 || n == 0 {
        Vec::new()
    } else {
        (0..options.save_frames.min(n))
            .map(|i| i * n / options.save_frames.min(n))
            .collect()
    };
    let input = replay.input(Arc::clone(render), save, options.frames_dir.clone())?;
    let mut builder = Reconstructor::builder()
        .intrinsics(*render.intrinsics())
        .pose_leak(!options.keep_pose_leak)
        .mouth_leak(!(options.keep_pose_leak || options.keep_mouth_leak));
    if let Some(dir) = &options.models {
        builder = builder.models_dir(dir);
    }
    let start = Instant::now();
    let mut sink = Collected::default();
    let outcome = builder.build_for(&input)?.run(input, &mut sink);
    let ms_per_frame = start.elapsed().as_secs_f64() * 1e3 / n.max(1) as f64;
    if let Some(source) = outcome.error {
        return Err(EvalError::ClipRun(Box::new(ClipRunError {
            clip: path.to_owned(),
            run: "expression replay",
            source,
        })));
    }
    let mut curves = Curves::default();
    let mut read_poses = Vec::new();
    let mut played_poses = Vec::new();
    let mut angle_errors: [Vec<f64>; 3] = Default::default();
    for (i, played) in replay.frames.iter().enumerate() {
        if let Some(b) = sink.weights.get(&i) {
            curves.time_s.push(played.time_s);
            curves.played.push(played.weights);
            curves.read.push(b.weights);
            curves.played_head.push(played.pose.angles);
            curves.read_head.push(b.head.map(f64::from));
            read_poses.push(live_link_rotation(b.head.map(f64::from)));
            played_poses.push(live_link_rotation(played.pose.angles));
            for (c, errors) in angle_errors.iter_mut().enumerate() {
                errors.push((f64::from(b.head[c]) - played.pose.angles[c]).to_degrees());
            }
        }
    }
    let rotation_errors: Vec<f64> = read_poses
        .iter()
        .zip(&played_poses)
        .map(|(r, p)| rotation_angle_deg(r, p))
        .collect();
    curves.played_from_rest = from_rest(&curves.played);
    let rest = rest_frames(&curves.played);
    let leak = rigid_leak(&curves.played, &curves.read, &rest);
    let identity_error_mm = match &outcome.identity {
        Some(fitted) => identity_error(model, &replay.identity, &fitted.neutral_mesh().vertices)?,
        None => None,
    };
    let shapes = shape_scores(&curves, Some(&rest));
    let blinks = blink_counts(&curves);
    let summary = ExpressionSummary {
        mae: mean_mae(&shapes, |s| s.mae),
        mae_from_rest: mean_mae(&shapes, |s| s.mae_from_rest),
        mae_floor: mean_mae(&shapes, |s| s.mae_floor),
        blink_hit_rate: blinks.hit_rate(),
        false_closure_rate: blinks.false_closure_rate(),
        blinks,
        rigid_leak_p99: (!leak.is_empty())
            .then(|| f64::from(quantile_sorted(&leak, LEAK_QUANTILE))),
        rigid_leak_worst: shapes
            .iter()
            .filter_map(|(name, s)| s.leak_p99.map(|v| (name.clone(), v)))
            .reduce(|a, b| if b.1 > a.1 { b } else { a }),
        head_rotation_rmse_deg: rms(&rotation_errors),
        head_angle_rmse_deg: match angle_errors.each_ref().map(|e| rms(e)) {
            [Some(y), Some(p), Some(r)] => Some([y, p, r]),
            _ => None,
        },
        identity_error_mm,
        frames: n,
        rest_frames: rest.len(),
        frames_with_face: curves.read.len(),
        ms_per_frame,
    };
    Ok(TakeResult {
        take: replay.name,
        summary,
        shapes,
        curves,
    })
}

/// Each shape's MAE and r over `curves`, and its leak over the frames at `rest` when given.
fn shape_scores(curves: &Curves, rest: Option<&[usize]>) -> BTreeMap<String, ShapeScore> {
    ARKIT_BLENDSHAPES
        .iter()
        .enumerate()
        .map(|(w, name)| {
            let played: Vec<f32> = curves.played.iter().map(|p| p[w]).collect();
            let read: Vec<f32> = curves.read.iter().map(|p| p[w]).collect();
            let relative: Vec<f32> = curves.played_from_rest.iter().map(|p| p[w]).collect();
            let leak_p99 = rest.and_then(|rest| {
                let one = |v: &[f32]| v.iter().map(|&x| [x]).collect::<Vec<[f32; 1]>>();
                let leak = rigid_leak(&one(&played), &one(&read), rest);
                (!leak.is_empty()).then(|| f64::from(quantile_sorted(&leak, LEAK_QUANTILE)))
            });
            (
                name.to_string(),
                ShapeScore {
                    mae: mae(&played, &read),
                    mae_from_rest: mae(&relative, &read),
                    mae_floor: mae(&played, &relative),
                    r: pearson(&played, &read),
                    leak_p99,
                },
            )
        })
        .collect()
}

/// The mean of the shapes' MAE, `tongueOut` left out (neither ICT nor the pipeline has it).
fn mean_mae(
    shapes: &BTreeMap<String, ShapeScore>,
    of: fn(&ShapeScore) -> Option<f64>,
) -> Option<f64> {
    let v: Vec<f64> = shapes
        .iter()
        .filter(|(name, _)| *name != "tongueOut")
        .filter_map(|(_, s)| of(s))
        .collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// Both eyes' blink counts.
fn blink_counts(curves: &Curves) -> BlinkCounts {
    ["eyeBlinkLeft", "eyeBlinkRight"]
        .iter()
        .filter_map(|name| ARKIT_BLENDSHAPES.iter().position(|n| n == name))
        .map(|w| {
            let played: Vec<f32> = curves.played.iter().map(|p| p[w]).collect();
            let read: Vec<f32> = curves.read.iter().map(|p| p[w]).collect();
            BlinkCounts::of(&played, &read)
        })
        .fold(BlinkCounts::default(), |a, b| a + b)
}

/// The fitted neutral face (`fitted`: the compact model's face region, ICT's vertex order)
/// against the rendered identity's, over the narrow face region, mm (see
/// [`ExpressionSummary::identity_error_mm`]).
fn identity_error(
    model: &IctModel,
    identity: &[f64],
    fitted: &[[f64; 3]],
) -> Result<Option<f64>, EvalError> {
    let mut truth = Vec::new();
    model.shape(
        identity,
        &vec![0.0; model.expression_modes.len()],
        &mut truth,
    )?;
    let narrow = Region::NarrowFace.range();
    if fitted.len() < narrow.end {
        return Ok(None);
    }
    Ok(aligned_rms(&fitted[narrow.clone()], &truth[narrow]).map(|m| m * 1e3))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_perfect_reading_relative_to_the_rest_scores_the_floor() {
        // A take resting at 0.3 of one shape, which rises to 1.0 for a quarter of its frames.
        let played: Vec<[f32; ARKIT_BLENDSHAPE_COUNT]> = (0..40)
            .map(|f| {
                let mut w = [0.0; ARKIT_BLENDSHAPE_COUNT];
                w[0] = if f % 4 == 0 { 1.0 } else { 0.3 };
                w
            })
            .collect();
        let relative = from_rest(&played);
        let curves = Curves {
            played_from_rest: relative.clone(),
            read: relative,
            played,
            ..Curves::default()
        };
        let s = shape_scores(&curves, None)[ARKIT_BLENDSHAPES[0]];
        assert_eq!(s.mae_from_rest, Some(0.0));
        // Rest frames are 0.3 off, the rest not at all: 0.3 × 3/4.
        let floor = s.mae_floor.unwrap();
        assert!((floor - 0.225).abs() < 1e-6, "{floor}");
        assert_eq!(s.mae, s.mae_floor);
    }
}
