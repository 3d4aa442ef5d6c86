//! A real clip run through the pipeline four ways — without the temporal model (the
//! per-frame fit), the default streaming smoother (one frame of latency), the causal smoother
//! (none) and clip mode — and the fused landmarks of each measured against the tracked ones
//! ([`evaluate_clip`]): what `visage eval video` reports per clip.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use visage::{
    Error, FrameMetrics, FrameSink, Input, LandmarksFrame, ModelSource, Reconstructor,
    TemporalMode, DEFAULT_FRAME_INTERVAL_S,
};

use crate::error::{ClipRunError, EvalError};
use crate::video_report::{evaluate_clip, ClipReport, ClipTracks, PipelineOutput};

/// The name of the run without the temporal model, the one the others are measured against.
const PER_FRAME: &str = "per-frame fit";

/// The four runs of a clip, in the order they are made and reported.
const RUNS: [&str; 4] = [PER_FRAME, "streaming", "causal", "clip"];

/// Segments shorter than this many frames are left out (jitter needs three).
const MIN_SEGMENT_FRAMES: usize = 3;

/// How the clips are read and the pipeline set up; the temporal model is each run's own.
#[derive(Clone, Debug)]
pub struct VideoOptions {
    /// Horizontal field of view (degrees).
    pub fov_deg: f64,
    /// Stop after this many frames per clip (`None`: the whole clip).
    pub max_frames: Option<usize>,
    /// The model directory (`None`: where `visage run` looks).
    pub models: Option<PathBuf>,
}

impl Default for VideoOptions {
    fn default() -> Self {
        VideoOptions {
            fov_deg: visage::DEFAULT_FOV_DEG,
            max_frames: None,
            models: None,
        }
    }
}

/// Runs the pipeline on `clip` (a video file or an image folder with one face) four ways and
/// measures each run's fused landmarks against the tracked ones, over the frames where every
/// run has a face, cut into segments at missing frames and shot cuts. The report is named
/// after the clip's file stem; the frame interval is the median step between timestamps.
///
/// # Errors
/// The pipeline's own error when the clip cannot be opened or the pipeline set up;
/// [`EvalError::ClipRun`] when a run stops part-way, [`EvalError::TrackingDiffers`] when a
/// run tracked other landmarks than the per-frame fit, [`EvalError::NoSegments`] when no
/// three consecutive frames show a face.
pub fn evaluate_video(clip: &Path, options: &VideoOptions) -> Result<ClipReport, EvalError> {
    let runs = RUNS
        .iter()
        .map(|run| run_once(options, clip, run))
        .collect::<Result<Vec<_>, _>>()?;
    let reference = &runs[0];
    for (collected, run) in runs.iter().zip(RUNS).skip(1) {
        if collected.tracked != reference.tracked {
            return Err(EvalError::TrackingDiffers {
                clip: clip.to_owned(),
                run,
                reference: PER_FRAME,
            });
        }
    }
    let segs = segments(reference, &runs.iter().collect::<Vec<_>>());
    if segs.is_empty() {
        return Err(EvalError::NoSegments {
            clip: clip.to_owned(),
        });
    }
    let times: Vec<f64> = reference.time_s.values().copied().collect();
    let mut steps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    let frame_interval_s = steps
        .get(steps.len() / 2)
        .copied()
        .filter(|d| *d > 0.0)
        .unwrap_or(DEFAULT_FRAME_INTERVAL_S);
    let pick = |map: &BTreeMap<usize, Vec<f64>>| -> Vec<Vec<Vec<f64>>> {
        segs.iter()
            .map(|s| s.iter().map(|i| map[i].clone()).collect())
            .collect()
    };
    let outputs = runs
        .iter()
        .zip(RUNS)
        .map(|(collected, run)| PipelineOutput {
            name: run.to_string(),
            latency_frames: match run {
                "clip" => None,
                "streaming" => Some(visage::DEFAULT_LATENCY_FRAMES),
                _ => Some(0),
            },
            landmarks: pick(&collected.fused),
            distance_m: segs
                .iter()
                .map(|s| s.iter().map(|i| collected.distance[i]).collect())
                .collect(),
        })
        .collect();
    let tracks = ClipTracks {
        name: clip.file_stem().map_or_else(
            || clip.display().to_string(),
            |s| s.to_string_lossy().into(),
        ),
        frame_interval_s,
        tracked: pick(&reference.tracked),
        outputs,
    };
    Ok(evaluate_clip(&tracks, PER_FRAME))
}

/// What one run of a clip gave, per frame index: the tracked and fused landmarks (`x, y`
/// scalars, pixels), the head's distance (metres), the timestamps (seconds) and the shot cuts.
#[derive(Default)]
struct Collected {
    tracked: BTreeMap<usize, Vec<f64>>,
    fused: BTreeMap<usize, Vec<f64>>,
    distance: BTreeMap<usize, f64>,
    time_s: BTreeMap<usize, f64>,
    cuts: Vec<usize>,
}

impl FrameSink for Collected {
    fn landmarks(&mut self, record: &LandmarksFrame) -> Result<(), Error> {
        let Some(face) = record.faces.first() else {
            return Ok(());
        };
        let flat = |p: &[[f64; 2]]| p.iter().flatten().copied().collect::<Vec<f64>>();
        let tracked: Vec<[f64; 2]> = face.landmarks.iter().map(|p| [p[0], p[1]]).collect();
        self.tracked.insert(record.index, flat(&tracked));
        if let Some(fused) = &face.fused_landmarks {
            if fused.iter().flatten().all(|v| v.is_finite()) {
                self.fused.insert(record.index, flat(fused));
            }
        }
        if let Some(pose) = &face.pose {
            self.distance.insert(record.index, pose.translation_m[2]);
        }
        Ok(())
    }

    fn frame_done(&mut self, m: &FrameMetrics) {
        if let Some(t) = m.time_s {
            self.time_s.insert(m.index, t);
        }
        if m.cut {
            self.cuts.push(m.index);
        }
    }
}

/// Runs the pipeline on `clip` once, with the temporal model `run` names (one of [`RUNS`]).
fn run_once(
    options: &VideoOptions,
    clip: &Path,
    run: &'static str,
) -> Result<Collected, EvalError> {
    let mut input = Input::open(clip)?;
    if let Some(m) = options.max_frames {
        input = input.max_frames(m)?;
    }
    let mut builder = Reconstructor::builder()
        .fov_deg(options.fov_deg)
        .model(ModelSource::None);
    if let Some(dir) = &options.models {
        builder = builder.models_dir(dir);
    }
    builder = match run {
        PER_FRAME => builder.landmark_smoothing(None),
        "causal" => builder.latency(0),
        "clip" => builder.mode(TemporalMode::Clip),
        _ => builder,
    };
    let mut sink = Collected::default();
    let outcome = builder.build_for(&input)?.run(input, &mut sink);
    if let Some(source) = outcome.error {
        return Err(EvalError::ClipRun(Box::new(ClipRunError {
            clip: clip.to_owned(),
            run,
            source,
        })));
    }
    Ok(sink)
}

/// Frames with tracked and fused landmarks on every run, cut into segments where frames are
/// missing or a shot starts; segments shorter than [`MIN_SEGMENT_FRAMES`] are dropped.
fn segments(reference: &Collected, runs: &[&Collected]) -> Vec<Vec<usize>> {
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut last: Option<usize> = None;
    for &i in reference.tracked.keys() {
        if !runs
            .iter()
            .all(|r| r.fused.contains_key(&i) && r.distance.contains_key(&i))
        {
            last = None;
            continue;
        }
        let follows = last.is_some_and(|l| l + 1 == i) && !reference.cuts.contains(&i);
        if !follows {
            out.push(Vec::new());
        }
        if let Some(seg) = out.last_mut() {
            seg.push(i);
        }
        last = Some(i);
    }
    out.retain(|s| s.len() >= MIN_SEGMENT_FRAMES);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run with a face on `frames`, fused landmarks and a distance on each.
    fn run_on(frames: &[usize], cuts: &[usize]) -> Collected {
        let mut run = Collected::default();
        for &i in frames {
            run.tracked.insert(i, vec![i as f64; 2]);
            run.fused.insert(i, vec![i as f64; 2]);
            run.distance.insert(i, 0.5);
        }
        run.cuts = cuts.to_vec();
        run
    }

    #[test]
    fn segments_break_at_gaps_and_cuts_and_drop_short_ones() {
        // 0–3 whole, a gap at 4, 5–6 too short, a gap at 7, 8–13 cut at 11.
        let frames = [0, 1, 2, 3, 5, 6, 8, 9, 10, 11, 12, 13];
        let reference = run_on(&frames, &[11]);
        let segs = segments(&reference, &[&reference]);
        assert_eq!(
            segs,
            vec![vec![0, 1, 2, 3], vec![8, 9, 10], vec![11, 12, 13]]
        );
    }

    /// The pipeline's error must stay in the chain (the binary finds internal errors there)
    /// and the printed chain must read as the pipeline's, with the run named first.
    #[test]
    fn errors_keep_the_pipelines_error_in_the_chain() {
        let internal = |e: &(dyn std::error::Error + 'static)| {
            let mut cause = Some(e);
            while let Some(c) = cause {
                if c.downcast_ref::<Error>().is_some_and(Error::is_internal) {
                    return true;
                }
                cause = c.source();
            }
            false
        };
        let failed = EvalError::ClipRun(Box::new(ClipRunError {
            clip: PathBuf::from("a/c.mp4"),
            run: "causal",
            source: Error::Panic("fuse"),
        }));
        assert!(internal(&failed));
        assert_eq!(
            visage::error_chain(&failed),
            "a/c.mp4: the causal run failed: internal error: the fuse stage panicked"
        );
        let setup = EvalError::from(Error::Input {
            path: PathBuf::from("a/c.mp4"),
            reason: "no frames".into(),
        });
        assert!(!internal(&setup));
        assert_eq!(visage::error_chain(&setup), "a/c.mp4: no frames");
    }

    #[test]
    fn segments_need_every_run() {
        let reference = run_on(&[0, 1, 2, 3, 4], &[]);
        // The other run lost the face at frame 2: no three consecutive frames remain.
        let other = run_on(&[0, 1, 3, 4], &[]);
        assert!(segments(&reference, &[&reference, &other]).is_empty());
    }
}
