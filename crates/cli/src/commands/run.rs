//! `visage run`: RGB video (or images) in, a fused metric face mesh per frame out (issue #6).
//!
//! Exit codes: 0 every frame processed; 2 bad input or environment — missing or unreadable
//! input, a video that breaks part-way (the readable frames are processed and written, the
//! message names the frame where decoding stopped), intrinsics for another image size,
//! an unwritable output folder, missing models; 1 an internal error. On any failure after the
//! output folder exists, `metrics.json` is still written, with `"status": "failed"` and the
//! error.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;
use visage_camera::{DepthKind, Intrinsics, DEFAULT_FOV_DEG};
use visage_face::{model_files, CanonicalMesh, FaceMesh, FaceTracker};
use visage_fem::{ClipOptions, Weights};
use visage_mesh::io::PlyFormat;
use visage_pipeline::{
    write_atomically, DepthSequence, MeshingOptions, PipelineError, ANCHORED_WEIGHTS_FACE,
    ANCHORED_WEIGHTS_MAP, DEFAULT_MAX_DEPTH_M,
};
use visage_video::{focal_length_35mm, is_image_path, read_image, FrameSource};

use crate::video_run::{
    run_pipeline, DepthSource, FrameMetrics, FusionParams, MeshKind, Output, RunConfig, RunOutcome,
    RunSummary, SurfaceFusion, TemporalMode,
};

/// Default subdivision of the FaceMesh template for `--mesh face` (≈ 1.8k vertices).
pub const DEFAULT_SUBDIVISION: usize = 2;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MeshArg {
    /// Face-anchored mesh, pose-compensated temporal term (default).
    Face,
    /// The paper's fixed image-plane mesh (domain: first face, dilated).
    Image,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ModeArg {
    /// Causal, frame by frame (live capture); memory independent of the clip length.
    Streaming,
    /// Exact minimiser over the clip; keeps every frame's system until the end.
    Clip,
}

/// The options `visage run` and `visage bench` share.
#[derive(Args, Debug)]
pub struct PipelineArgs {
    /// A video file (decoded by FFmpeg), a folder of images (name order) or one image.
    pub input: PathBuf,
    /// Camera intrinsics JSON ({"width","height","fx","fy","cx","cy"}) for the input's size.
    #[arg(long, conflicts_with = "fov_deg")]
    pub intrinsics: Option<PathBuf>,
    /// Horizontal field of view (degrees) when no intrinsics file is given. Default: the
    /// 35 mm-equivalent focal length in an image input's EXIF if present, else 60°.
    #[arg(long)]
    pub fov_deg: Option<f64>,
    /// Depth source: `face` (the metric face fit, the face-CNN surface) or a folder of 16-bit
    /// PNG depth maps (millimetres, z), the i-th file for input frame i.
    #[arg(long, default_value = "face")]
    pub depth: String,
    /// Smoothness weight λ (face mesh: mm⁴ of the canonical face, default 1 with the face
    /// depth and 10 with depth maps; image mesh: reference pixels⁴, default 10).
    #[arg(long, allow_hyphen_values = true)]
    pub lambda: Option<f64>,
    /// Temporal weight μ (dimensionless; default 0.5, face mesh with depth maps 1).
    #[arg(long, allow_hyphen_values = true)]
    pub mu: Option<f64>,
    /// Mesh design.
    #[arg(long, value_enum, default_value = "face")]
    pub mesh: MeshArg,
    /// Temporal model.
    #[arg(long, value_enum, default_value = "streaming")]
    pub mode: ModeArg,
    /// Face mesh: subdivision of the FaceMesh template (1–16; n² triangles per template
    /// triangle).
    #[arg(long, default_value_t = DEFAULT_SUBDIVISION)]
    pub subdivision: usize,
    /// Image mesh: grid spacing in pixels.
    #[arg(long, default_value_t = MeshingOptions::default().spacing)]
    pub spacing: u32,
    /// Process every N-th input frame (frames keep their input index).
    #[arg(long, default_value_t = 1)]
    pub every: usize,
    /// Stop after this many processed frames.
    #[arg(long)]
    pub max_frames: Option<usize>,
    /// Model directory; default: $VISAGE_MODELS, else ./models or a models/ folder beside the
    /// executable (see `visage models fetch`).
    #[arg(long)]
    pub models: Option<PathBuf>,
    /// No progress bar and no closing line.
    #[arg(long)]
    pub quiet: bool,
}

/// Arguments of `visage run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    /// Output folder: meshes/NNNNNN.ply, raw/ (with --save-raw), landmarks.json, metrics.json,
    /// camera.json (the intrinsics used).
    #[arg(long)]
    pub out: PathBuf,
    /// Also write the raw (unfused) surface on the same mesh to OUT/raw/.
    #[arg(long)]
    pub save_raw: bool,
    /// Write ASCII PLY instead of binary.
    #[arg(long)]
    pub ascii: bool,
}

/// `metrics.json`.
#[derive(Serialize)]
struct RunReport<'a> {
    /// `"complete"` or `"failed"` (then `error` says why; frames up to the failure are listed).
    status: &'static str,
    error: Option<String>,
    input: String,
    intrinsics: Intrinsics,
    parameters: &'a FusionParams,
    mode: TemporalMode,
    depth: &'a str,
    mesh_vertices: usize,
    summary: &'a RunSummary,
    frames: &'a [FrameMetrics],
}

/// Runs `visage run`.
pub fn run(args: RunArgs) -> anyhow::Result<()> {
    let p = &args.pipeline;
    let start = Instant::now();
    check_input(&p.input)?;
    let models = p.models.clone().unwrap_or_else(model_files::models_dir);
    let canonical = CanonicalMesh::load(&models)?;
    // Output folder first: an unwritable one stops the run before any work.
    for sub in ["meshes"].into_iter().chain(args.save_raw.then_some("raw")) {
        let dir = args.out.join(sub);
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create the output folder {}", dir.display()))?;
    }
    let output = Output::Files {
        dir: args.out.clone(),
        save_raw: args.save_raw,
        format: if args.ascii {
            PlyFormat::Ascii
        } else {
            PlyFormat::BinaryLittleEndian
        },
    };
    let (outcome, params, k, vertices) = execute(p, &canonical, &models, output, start)?;
    let report = RunReport {
        status: if outcome.error.is_some() {
            "failed"
        } else {
            "complete"
        },
        error: outcome.error.as_ref().map(|e| format!("{e:#}")),
        input: p.input.display().to_string(),
        intrinsics: k,
        parameters: &params,
        mode: mode(p.mode),
        depth: &p.depth,
        mesh_vertices: vertices,
        summary: &outcome.summary,
        frames: &outcome.frames,
    };
    // The camera the meshes are in: `visage render MESH --intrinsics OUT/camera.json`.
    let camera_path = args.out.join("camera.json");
    k.save_json(&camera_path)
        .with_context(|| format!("cannot write {}", camera_path.display()))?;
    let metrics_path = args.out.join("metrics.json");
    let text = serde_json::to_string_pretty(&report)?;
    write_atomically(&metrics_path, |tmp: &Path| {
        std::fs::write(tmp, &text).map_err(|source| PipelineError::Io {
            path: tmp.to_owned(),
            source,
        })
    })
    .with_context(|| format!("cannot write {}", metrics_path.display()))?;
    if let Some(e) = outcome.error {
        return Err(e.context(format!(
            "stopped after {} frames (meshes so far and metrics.json are in {})",
            outcome.frames.len(),
            args.out.display()
        )));
    }
    if !p.quiet {
        let s = &outcome.summary;
        eprintln!(
            "{} frames ({} meshed, {} without a face) → {}; {:.1} fps, CPU {:.2}, peak RSS {:.0} MiB; jitter fused {:.3} mm vs raw {:.3} mm",
            s.frames,
            s.solved + s.carried,
            s.no_face,
            args.out.display(),
            s.fps,
            s.cpu_use.unwrap_or(0.0),
            s.peak_rss_mib.unwrap_or(0.0),
            s.quality.vertex_jitter_mm.fused.unwrap_or(0.0),
            s.quality.vertex_jitter_mm.raw.unwrap_or(0.0),
        );
    }
    Ok(())
}

/// Fails (naming the path) when the input does not exist, before models are loaded.
pub fn check_input(input: &Path) -> anyhow::Result<()> {
    std::fs::metadata(input)
        .map(|_| ())
        .with_context(|| format!("{}: cannot read the input", input.display()))
}

fn mode(m: ModeArg) -> TemporalMode {
    match m {
        ModeArg::Streaming => TemporalMode::Streaming,
        ModeArg::Clip => TemporalMode::Clip,
    }
}

/// Validates the options, sets up tracker and fusion, and runs the pipeline. Returns the
/// outcome, the parameters, the intrinsics and the mesh size (0 if no mesh was built).
pub fn execute(
    p: &PipelineArgs,
    canonical: &CanonicalMesh,
    models: &Path,
    output: Output,
    start: Instant,
) -> anyhow::Result<(RunOutcome, FusionParams, Intrinsics, usize)> {
    let defaults = match (p.mesh, p.depth.as_str()) {
        (MeshArg::Face, "face") => ANCHORED_WEIGHTS_FACE,
        (MeshArg::Face, _) => ANCHORED_WEIGHTS_MAP,
        (MeshArg::Image, _) => Weights::default(),
    };
    let weights = Weights {
        lambda: p.lambda.unwrap_or(defaults.lambda),
        mu: p.mu.unwrap_or(defaults.mu),
    };
    weights.validate().context("invalid --lambda/--mu")?;
    if p.every == 0 {
        bail!("--every 0: must be at least 1");
    }
    if p.max_frames == Some(0) {
        bail!("--max-frames 0: must be at least 1");
    }
    let fov = p.fov_deg.unwrap_or(DEFAULT_FOV_DEG);
    if !(fov.is_finite() && fov > 0.0 && fov < 180.0) {
        bail!("--fov-deg {fov}: must lie strictly between 0 and 180");
    }
    let source = FrameSource::open(&p.input)?;
    let (width, height, expected) = input_size(&p.input, &source)?;
    let k = match &p.intrinsics {
        Some(path) => {
            let k = Intrinsics::load_json(path)?;
            k.check_size(width, height).with_context(|| {
                format!(
                    "{}: intrinsics are for another image size than {} ({width}×{height})",
                    path.display(),
                    p.input.display()
                )
            })?;
            k
        }
        None => match (p.fov_deg, exif_focal(&source)) {
            (None, Some((path, f35))) => {
                eprintln!(
                    "intrinsics: {f35} mm (35 mm equivalent) from the EXIF of {}",
                    path.display()
                );
                Intrinsics::from_focal_35mm(width, height, f35)?
            }
            _ => Intrinsics::from_fov(width, height, fov)?,
        },
    };
    let depth = match p.depth.as_str() {
        "face" => DepthSource::Face,
        dir => DepthSource::Dir(
            DepthSequence::open(Path::new(dir), 1000.0, DepthKind::Z)
                .context("cannot use --depth")?,
        ),
    };
    let params = FusionParams {
        mesh: match p.mesh {
            MeshArg::Face => MeshKind::Face,
            MeshArg::Image => MeshKind::Image,
        },
        weights,
        subdivision: p.subdivision,
        meshing: MeshingOptions {
            spacing: p.spacing,
            ..MeshingOptions::default()
        },
        max_depth_m: DEFAULT_MAX_DEPTH_M,
    };
    let tracker = FaceTracker::new(FaceMesh::load(models)?);
    let fusion = SurfaceFusion::new(params, canonical, k)?;
    let vertices = fusion.vertex_count();
    let total = expected
        .map(|n| n.div_ceil(p.every))
        .map(|n| p.max_frames.map_or(n, |m| n.min(m)));
    let progress = if p.quiet {
        ProgressBar::hidden()
    } else {
        let bar =
            ProgressBar::with_draw_target(total.map(|n| n as u64), ProgressDrawTarget::stderr());
        if let Ok(style) =
            ProgressStyle::with_template("{bar:40} {pos}/{len} frames  {per_sec}  eta {eta}")
        {
            bar.set_style(style);
        }
        bar
    };
    let config = RunConfig {
        k,
        canonical,
        depth,
        mode: mode(p.mode),
        clip: ClipOptions::default(),
        every: p.every,
        max_frames: p.max_frames,
        output,
        progress,
    };
    let setup_ms = start.elapsed().as_secs_f64() * 1e3;
    let outcome = run_pipeline(&config, source, tracker, fusion, setup_ms);
    let vertices = outcome.vertices.max(vertices);
    Ok((outcome, params, k, vertices))
}

/// The display size of the input's frames and, when known, the number of frames.
/// The 35 mm-equivalent focal length in the EXIF of an image input's first image, if any.
fn exif_focal(source: &FrameSource) -> Option<(PathBuf, f64)> {
    match source {
        FrameSource::Images { paths, .. } => {
            let first = paths.first()?;
            focal_length_35mm(first).map(|f| (first.clone(), f))
        }
        FrameSource::Video(_) => None,
    }
}

fn input_size(input: &Path, source: &FrameSource) -> anyhow::Result<(u32, u32, Option<usize>)> {
    match source {
        FrameSource::Video(reader) => {
            let info = reader.info();
            Ok((info.width, info.height, info.frame_count))
        }
        FrameSource::Images { paths, .. } => {
            let first = paths
                .first()
                .with_context(|| format!("{}: no images", input.display()))?;
            let (w, h) = if is_image_path(first) {
                read_image(first)?.image.dimensions()
            } else {
                bail!("{}: not an image", first.display());
            };
            Ok((w, h, Some(paths.len())))
        }
    }
}
