//! `visage eval video`: the temporal model on real clips against the filters a user could
//! apply to the tracked landmarks instead (`visage_eval::evaluate_clip`). Each clip is run
//! four ways — without the temporal model (the per-frame fit), the default streaming
//! smoother (one frame of latency), the causal smoother (none) and clip mode — and the
//! fused landmarks of each are measured against the tracked ones.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use visage::{
    Error, FrameMetrics, FrameSink, Input, LandmarksFrame, ModelSource, Reconstructor,
    TemporalMode, DEFAULT_FRAME_INTERVAL_S,
};
use visage_eval::{
    evaluate_clip, stability_chart_svg, stability_table, ClipReport, ClipTracks, PipelineOutput,
};

/// Arguments of `visage eval video`.
#[derive(Args, Debug)]
pub struct VideoArgs {
    /// Video files (or image folders) with one face.
    #[arg(required = true)]
    pub clips: Vec<PathBuf>,
    /// Output folder (created): results.json and one CLIP_stability.svg per clip.
    #[arg(long)]
    pub out: PathBuf,
    /// Horizontal field of view (degrees).
    #[arg(long, default_value_t = visage::DEFAULT_FOV_DEG)]
    pub fov_deg: f64,
    /// Stop after this many frames per clip.
    #[arg(long)]
    pub max_frames: Option<usize>,
    /// Model directory (default: as `visage run`).
    #[arg(long)]
    pub models: Option<PathBuf>,
}

/// The name of the run without the temporal model.
const PER_FRAME: &str = "per-frame fit";

/// What one run of a clip gave, per frame index.
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

fn run_once(args: &VideoArgs, clip: &Path, name: &str) -> anyhow::Result<Collected> {
    let mut input = Input::open(clip)?;
    if let Some(m) = args.max_frames {
        input = input.max_frames(m)?;
    }
    let mut builder = Reconstructor::builder()
        .fov_deg(args.fov_deg)
        .model(ModelSource::None);
    if let Some(dir) = &args.models {
        builder = builder.models_dir(dir);
    }
    builder = match name {
        PER_FRAME => builder.landmark_smoothing(None),
        "causal" => builder.latency(0),
        "clip" => builder.mode(TemporalMode::Clip),
        _ => builder,
    };
    let mut sink = Collected::default();
    let outcome = builder.build_for(&input)?.run(input, &mut sink);
    if let Some(e) = outcome.error {
        return Err(e).with_context(|| format!("{}: the {name} run failed", clip.display()));
    }
    Ok(sink)
}

/// Frames with tracked and fused landmarks on both runs, cut into segments where frames are
/// missing or a shot starts.
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
    out.retain(|s| s.len() >= 3);
    out
}

fn evaluate(args: &VideoArgs, clip: &Path) -> anyhow::Result<ClipReport> {
    let names = [PER_FRAME, "streaming", "causal", "clip"];
    let runs = names
        .iter()
        .map(|n| run_once(args, clip, n))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let reference = &runs[0];
    for (run, name) in runs.iter().zip(names).skip(1) {
        anyhow::ensure!(
            run.tracked == reference.tracked,
            "{}: the {name} run tracked other landmarks than the {PER_FRAME} run",
            clip.display()
        );
    }
    let segs = segments(reference, &runs.iter().collect::<Vec<_>>());
    anyhow::ensure!(
        !segs.is_empty(),
        "{}: no three consecutive frames with a face",
        clip.display()
    );
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
        .zip(names)
        .map(|(run, name)| PipelineOutput {
            name: name.to_string(),
            latency_frames: match name {
                "clip" => None,
                "streaming" => Some(visage::DEFAULT_LATENCY_FRAMES),
                _ => Some(0),
            },
            landmarks: pick(&run.fused),
            distance_m: segs
                .iter()
                .map(|s| s.iter().map(|i| run.distance[i]).collect())
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

/// Runs `visage eval video`.
pub fn video(args: VideoArgs) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let mut reports = Vec::new();
    for clip in &args.clips {
        let report = evaluate(&args, clip)?;
        let svg = args.out.join(format!("{}_stability.svg", report.clip));
        let text = stability_chart_svg(&report);
        visage::write_atomically(&svg, |tmp| {
            std::fs::write(tmp, &text).map_err(|source| visage::run_folder::RunFolderError::Write {
                path: svg.clone(),
                source,
            })
        })?;
        reports.push(report);
    }
    visage::write_json_atomically(&args.out.join("results.json"), &reports)?;
    print!("{}", stability_table(&reports));
    Ok(())
}
