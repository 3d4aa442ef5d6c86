//! `visage export`: the files people open, made from a run's output folder — the animated
//! glTF, the fused face texture — and the flags `visage run` shares to make them at once.

use std::path::{Path, PathBuf};

use clap::Args;
use visage_export::{export, ExportOptions, ExportSummary};

/// The exports `visage run` can make after the run (`visage export` makes them later).
#[derive(Args, Debug, Default)]
pub struct ExportArgs {
    /// Write OUT/sequence.glb: the face mesh with its texture, animated (morph targets and
    /// head motion) at the video's frame times — for Blender, Unreal, Unity, three.js.
    #[arg(long)]
    pub glb: bool,
    /// Write OUT/texture.png: the face's colour fused from the frames (mesh.mtl names it).
    #[arg(long)]
    pub texture: bool,
    /// Write OUT/plots/*.svg and *.png: per-frame time by stage, frame rate, curvature,
    /// roughness, jitter and the blendshape curves.
    #[arg(long)]
    pub plots: bool,
    /// Write OUT/report.html: one page that opens offline — summary, renders, the plots and
    /// a 3-D viewer playing the animation (also writes the glb, texture and plots).
    #[arg(long)]
    pub report: bool,
    /// Write OUT/preview.mp4: the input | the shaded mesh over it | the mesh turning, side by
    /// side (renders every frame: slower than the other exports).
    #[arg(long)]
    pub preview: bool,
}

impl ExportArgs {
    /// The flags as the library's options.
    pub fn options(&self) -> ExportOptions {
        ExportOptions {
            glb: self.glb,
            texture: self.texture,
            plots: self.plots,
            report: self.report,
            preview: self.preview,
        }
    }
}

/// Arguments of `visage export`.
#[derive(Args, Debug)]
pub struct ExportCommandArgs {
    /// A `visage run` output folder (its sequence.pc2, mesh.obj, camera.json, metrics.json;
    /// the input it names is read again for the texture).
    pub dir: PathBuf,
    #[command(flatten)]
    pub exports: ExportArgs,
    /// No summary line.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs `visage export` (everything but the preview video when no export is named).
pub fn run(args: ExportCommandArgs) -> anyhow::Result<()> {
    let mut exports = args.exports.options();
    if !exports.any() {
        exports = ExportOptions {
            report: true,
            glb: true,
            texture: true,
            plots: true,
            preview: false,
        };
    }
    // One writer at a time in a run's folder (a run still going there, another export).
    let _lock = visage::run_folder::inspect(&args.dir)?
        .written_by_visage()
        .then(|| visage::run_folder::FolderLock::acquire(&args.dir))
        .transpose()?;
    let summary = export(&args.dir, &exports, None)?;
    if !args.quiet {
        print_summary(&args.dir, &summary);
    }
    Ok(())
}

/// One line per file written, with its size and time.
pub fn print_summary(dir: &Path, summary: &ExportSummary) {
    for f in &summary.files {
        eprintln!(
            "{}: {:.2} MB in {:.0} ms",
            dir.join(&f.file).display(),
            f.bytes as f64 / 1e6,
            f.ms
        );
    }
    if let (Some(rms), Some(max)) = (summary.glb_rms_error_m, summary.glb_max_error_m) {
        eprintln!(
            "{}: {} morph targets ({} ARKit), {:.3} mm RMS from the point cache (largest \
             {:.3} mm)",
            visage::file_names::GLB,
            summary.named_targets + summary.residual_targets,
            summary.named_targets,
            rms * 1e3,
            max * 1e3
        );
    }
}
