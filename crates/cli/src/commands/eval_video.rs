//! `visage eval video`: the temporal model on real clips against the filters a user could
//! apply to the tracked landmarks instead. Each clip is run four ways by
//! `visage_eval::evaluate_video`; this writes the charts and `results.json` and prints the
//! table.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use visage_eval::{evaluate_video, stability_chart_svg, stability_table, VideoOptions};

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

/// Runs `visage eval video`.
pub fn video(args: VideoArgs) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let options = VideoOptions {
        fov_deg: args.fov_deg,
        max_frames: args.max_frames,
        models: args.models,
    };
    let mut reports = Vec::new();
    for clip in &args.clips {
        let report = evaluate_video(clip, &options)?;
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
