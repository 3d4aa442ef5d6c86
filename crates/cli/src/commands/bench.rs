//! `visage bench`: the `visage run` pipeline without writing meshes or landmarks (decode,
//! tracking, fit, depth and fusion all run, and the quality figures are measured), timed per
//! stage; JSON on standard output and optionally in a file.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use serde_json::json;

use super::run::{terminal, PipelineArgs};

/// Arguments of `visage bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    /// Also write the JSON to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Runs `visage bench`.
pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    let p = &args.pipeline;
    p.options().check_input(p.input_path())?;
    let (input, reconstructor) = p.open()?;
    let bar = p.progress(&input);
    // Ctrl-C ends the input; the figures cover the frames so far.
    let input = input.stop_on(crate::interrupt::install("no figures were printed"));
    let outcome = reconstructor.run(input, &mut terminal(&bar));
    bar.finish_and_clear();
    if let Some(e) = outcome.error {
        return Err(anyhow::Error::new(e).context(format!(
            "benchmark stopped after {} frames",
            outcome.frames.len()
        )));
    }
    let s = &outcome.summary;
    let doc = json!({
        "input": p.input_path().display().to_string(),
        "width": outcome.intrinsics.width,
        "height": outcome.intrinsics.height,
        "parameters": outcome.parameters,
        "mesh_vertices": outcome.mesh.vertices,
        "writes_meshes": false,
        "frames": s.frames,
        "fps": s.fps,
        "wall_s": s.wall_s,
        "setup_ms": s.setup_ms,
        "cpu_s": s.cpu_s,
        "cpu_use": s.cpu_use,
        "cpu_ms_per_frame": s.cpu_ms_per_frame,
        "threads": std::thread::available_parallelism().map(|n| n.get()).ok(),
        "network_kernels": visage_nn::ops::kernels(),
        "peak_rss_mib": s.peak_rss_mib,
        "detector_runs": s.detector_runs,
        "stages_ms": s.stages,
        "quality": s.quality,
        "keypoint_motion": s.keypoint_motion,
        "depth_alignment": s.depth_alignment,
    });
    let text = serde_json::to_string_pretty(&doc)?;
    println!("{text}");
    if let Some(path) = &args.out {
        std::fs::write(path, &text).with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}
