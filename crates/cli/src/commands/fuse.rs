//! `visage fuse`: reconstruct a mesh sequence from 16-bit PNG depth maps.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, ValueEnum};
use visage::{
    fuse_depth_folder, ClipOptions, DepthKind, DepthSequence, FuseOptions, Intrinsics,
    MeshingOptions, TemporalMode, TriangulationKind, Weights, DEFAULT_FOV_DEG, DEFAULT_MAX_DEPTH_M,
};

use super::run::ModeArg;
use crate::progress::progress_bar;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum DepthKindArg {
    /// z coordinate (Kinect, RealSense, TUM).
    Z,
    /// Distance along the ray (the paper's D).
    Ray,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum TriangulationArg {
    Planar,
    DepthAware,
    Auto,
}

/// Arguments of `visage fuse`.
#[derive(Args, Debug)]
pub struct FuseArgs {
    /// Folder of 16-bit PNG depth frames, processed in name order.
    #[arg(long)]
    depth: PathBuf,
    /// Camera intrinsics JSON ({"width","height","fx","fy","cx","cy"}); default: --fov-deg.
    #[arg(long)]
    intrinsics: Option<PathBuf>,
    /// Horizontal field of view (degrees) when no intrinsics file is given.
    #[arg(long, default_value_t = DEFAULT_FOV_DEG)]
    fov_deg: f64,
    /// Output folder (meshes/, raw/, metrics.json).
    #[arg(long)]
    out: PathBuf,
    /// Stored value / depth-scale = metres.
    #[arg(long, default_value_t = 1000.0)]
    depth_scale: f64,
    /// What the depth values measure.
    #[arg(long, value_enum, default_value = "z")]
    depth_kind: DepthKindArg,
    /// Depth beyond this many metres counts as missing.
    #[arg(long, default_value_t = DEFAULT_MAX_DEPTH_M)]
    max_depth: f64,
    /// Smoothness weight λ (reference pixels⁴; see ARCHITECTURE.md).
    #[arg(long, default_value_t = Weights::default().lambda, allow_hyphen_values = true)]
    lambda: f64,
    /// Temporal weight μ (dimensionless).
    #[arg(long, default_value_t = Weights::default().mu, allow_hyphen_values = true)]
    mu: f64,
    /// Temporal model.
    #[arg(long, value_enum, default_value = "streaming")]
    mode: ModeArg,
    /// Relative residual at which clip mode stops.
    #[arg(long, default_value_t = ClipOptions::default().tolerance)]
    clip_tolerance: f64,
    /// Mesh grid spacing in pixels.
    #[arg(long, default_value_t = MeshingOptions::default().spacing)]
    spacing: u32,
    /// Triangulation variant (auto: depth-aware when depth range / mean depth > 0.15).
    #[arg(long, value_enum, default_value = "auto")]
    triangulation: TriangulationArg,
    /// Extra samples where the depth deviates from the mesh by more than this (mm); 0 = off.
    #[arg(long, default_value_t = 1.0)]
    refine_mm: f64,
    /// Also write the data term's target on the same mesh to OUT/raw/.
    #[arg(long)]
    save_raw: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

pub fn run(args: FuseArgs) -> anyhow::Result<()> {
    let kind = match args.depth_kind {
        DepthKindArg::Z => DepthKind::Z,
        DepthKindArg::Ray => DepthKind::Ray,
    };
    let weights = Weights {
        lambda: args.lambda,
        mu: args.mu,
    };
    weights.validate().context("invalid weights")?;
    if !(args.refine_mm.is_finite() && args.refine_mm >= 0.0) {
        anyhow::bail!("invalid --refine-mm {}: must be ≥ 0", args.refine_mm);
    }
    if !(args.clip_tolerance.is_finite() && args.clip_tolerance > 0.0) {
        anyhow::bail!(
            "invalid --clip-tolerance {}: must be > 0",
            args.clip_tolerance
        );
    }
    let sequence = DepthSequence::open(&args.depth, args.depth_scale, kind)?;
    let k = match &args.intrinsics {
        Some(path) => Intrinsics::load_json(path)?,
        None => {
            let first = sequence.read(0)?;
            Intrinsics::from_fov(first.width, first.height, args.fov_deg)?
        }
    };
    let options = FuseOptions {
        weights,
        mode: match args.mode {
            ModeArg::Streaming => TemporalMode::Streaming,
            ModeArg::Clip => TemporalMode::Clip,
        },
        meshing: MeshingOptions {
            spacing: args.spacing,
            triangulation: match args.triangulation {
                TriangulationArg::Planar => TriangulationKind::Planar,
                TriangulationArg::DepthAware => TriangulationKind::DepthAware,
                TriangulationArg::Auto => TriangulationKind::Auto,
            },
            refine_tolerance_m: (args.refine_mm > 0.0).then_some(args.refine_mm * 1e-3),
        },
        depth_kind: kind,
        depth_scale: args.depth_scale,
        max_depth_m: args.max_depth,
        clip: ClipOptions {
            tolerance: args.clip_tolerance,
            ..ClipOptions::default()
        },
    };
    let context = || {
        let intrinsics = args.intrinsics.as_ref().map_or_else(
            || format!("--fov-deg {}", args.fov_deg),
            |p| p.display().to_string(),
        );
        format!(
            "fusing {} with intrinsics {intrinsics}",
            args.depth.display()
        )
    };
    let bar = progress_bar(args.quiet, Some(sequence.frames.len()));
    let report = fuse_depth_folder(
        &sequence,
        &k,
        &options,
        &args.out,
        args.save_raw,
        &mut |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
        &mut |warning| bar.suspend(|| eprintln!("warning: {warning}")),
    )
    .with_context(context)?;
    bar.finish_and_clear();
    if !args.quiet {
        let s = &report.summary;
        eprintln!(
            "{} frames ({} solved, {} carried, {} without data) → {}; mesh {} vertices, \
             median fusion {:.2} ms, curvature improvement {:.1}×",
            s.frames,
            s.solved,
            s.carried,
            s.no_data,
            args.out.display(),
            report.mesh.vertices,
            s.stages.get("fuse").map_or(0.0, |p| p.median_ms),
            s.mean_curvature_improvement
        );
    }
    Ok(())
}
