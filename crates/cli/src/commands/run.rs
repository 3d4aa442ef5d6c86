//! `visage run`: a video, image folder or image in, a fused metric face mesh per frame out.
//!
//! Exit codes: 0 every frame processed; 2 bad input or environment — missing or unreadable
//! input, a video that breaks part-way (the readable frames are processed and written, the
//! message names the frame where decoding stopped), intrinsics for another image size, an
//! unwritable output folder, missing models; 1 an internal error. On any failure after the
//! output folder exists, `metrics.json` is still written, with `"status": "failed"` and the
//! error.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use indicatif::ProgressBar;
use visage::{
    file_names, ClipProgress, FaceRun, FaceTarget, Faces, FrameMetrics, FrameSink, Input, MeshKind,
    ModelSource, PipelineOptions, Reconstructor, RunOptions, TemporalMode, DEFAULT_SUBDIVISION,
};

use crate::commands::export::{print_summary, ExportArgs};
use crate::exit::Failure;
use crate::interrupt;
use crate::progress::progress_bar;

/// Mesh design.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MeshArg {
    /// Face-anchored mesh, pose-compensated temporal term (default).
    Face,
    /// The paper's fixed image-plane mesh (domain: first face, dilated).
    Image,
    /// The fitted face model's mesh (this person's face; UVs).
    Model,
}

/// Temporal model.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ModeArg {
    /// Causal, frame by frame (live capture); memory independent of the clip length.
    Streaming,
    /// Exact minimiser over the clip; keeps every frame's system until the end.
    Clip,
}

/// `--smoothing`: a positive ratio or `off`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothingArg(pub Option<f64>);

impl std::str::FromStr for SmoothingArg {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        if s == "off" {
            return Ok(SmoothingArg(None));
        }
        match s.parse::<f64>() {
            Ok(r) if r.is_finite() && r > 0.0 => Ok(SmoothingArg(Some(r))),
            _ => Err(format!("{s:?} is neither a positive number nor \"off\"")),
        }
    }
}

impl std::fmt::Display for SmoothingArg {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0 {
            Some(r) => write!(f, "{r}"),
            None => f.write_str("off"),
        }
    }
}

/// The options `visage run` and `visage bench` share.
#[derive(Args, Debug)]
pub struct PipelineArgs {
    /// A video file (decoded by FFmpeg), a folder of images (name order) or one image (with
    /// --rgbd: omitted, the recording's colour frames are the input).
    #[arg(required_unless_present = "rgbd", conflicts_with = "rgbd")]
    pub input: Option<PathBuf>,
    /// An RGB-D recording as the input: the TUM RGB-D layout (rgb.txt, depth.txt; depth PNGs
    /// at 5000 per metre) or the folders rgb/ and depth/ (16-bit PNG depth in millimetres;
    /// file names that are numbers are timestamps in seconds, else the two pair in name
    /// order). Colour and depth are associated by timestamp (within 20 ms), each colour frame
    /// fused with its depth map; flying pixels at depth edges and hole rims are masked.
    /// Without --intrinsics a TUM recording gets its dataset's default camera (525 px, centre
    /// 319.5, 239.5).
    #[arg(long, value_name = "DIR", conflicts_with = "depth")]
    pub rgbd: Option<PathBuf>,
    /// Depth units per metre of depth PNGs (default: 5000 for a TUM recording, else 1000).
    #[arg(long, value_name = "UNITS")]
    pub depth_scale: Option<f64>,
    /// With --rgbd: the depth camera's intrinsics JSON; the depth is then registered to the
    /// colour camera (--intrinsics), moved by --depth-to-color.
    #[arg(long, value_name = "FILE", requires = "rgbd", requires = "intrinsics")]
    pub depth_intrinsics: Option<PathBuf>,
    /// With --depth-intrinsics: the rigid motion from depth to colour camera coordinates
    /// ({"rotation": [[…], […], […]], "translation": [x, y, z]}, metres; default none).
    #[arg(long, value_name = "FILE", requires = "depth_intrinsics")]
    pub depth_to_color: Option<PathBuf>,
    /// With --rgbd: use every depth value, flying pixels and hole rims included.
    #[arg(long, requires = "rgbd")]
    pub keep_depth_edges: bool,
    /// With --depth MODEL.onnx: the network's description (JSON) when it is not MODEL.json
    /// beside the network.
    #[arg(long, value_name = "FILE")]
    pub depth_config: Option<PathBuf>,
    /// Camera intrinsics JSON ({"width","height","fx","fy","cx","cy"}) for the input's size.
    #[arg(long, conflicts_with = "fov_deg")]
    pub intrinsics: Option<PathBuf>,
    /// Horizontal field of view (degrees) when no intrinsics file is given. Default: the
    /// 35 mm-equivalent focal length in an image input's EXIF if present, else 60°.
    #[arg(long)]
    pub fov_deg: Option<f64>,
    /// Depth source: `face` (the metric face fit's surface), `model` (the fitted face
    /// model's surface), a depth network (`MODEL.onnx`, described by MODEL.json beside it or
    /// --depth-config: input size, colour order, normalisation, and whether it gives metric
    /// depth, relative depth, inverse depth or disparity; outputs that are not metric are
    /// aligned to the fitted face every frame), or a folder of 16-bit PNG depth maps
    /// (millimetres, z; see --depth-scale), the i-th file for input frame i.
    #[arg(long, default_value = "face")]
    pub depth: String,
    /// Smoothness weight λ ([`weight_help`] writes this help from the defaults).
    #[arg(long, allow_hyphen_values = true)]
    pub lambda: Option<f64>,
    /// Temporal weight μ ([`weight_help`] writes this help from the defaults).
    #[arg(long, allow_hyphen_values = true)]
    pub mu: Option<f64>,
    /// The temporal model of the tracked landmarks: a constant-velocity Kalman filter with
    /// this acceleration-to-noise ratio (1/s²; larger follows faster motion and smooths
    /// less), or `off` to use every frame's landmarks as tracked.
    #[arg(long, default_value_t = SmoothingArg(Some(visage::DEFAULT_LANDMARK_SMOOTHING)))]
    pub smoothing: SmoothingArg,
    /// Frames the landmark smoother waits for before giving a frame out (0: causal, each
    /// frame at once; 1 lets each frame see where the motion went next).
    #[arg(long, default_value_t = visage::DEFAULT_LATENCY_FRAMES)]
    pub latency: usize,
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
    /// Fair every fused surface (Willmore-type smoothing, as `visage fair`) with this smoothing
    /// length in millimetres.
    #[arg(long, value_name = "LENGTH_MM")]
    pub fair: Option<f64>,
    /// Check every frame's head motion against SIFT keypoints on the face (matched with the
    /// previous frame's, lifted onto the fitted face, a rigid motion by RANSAC); metrics.json
    /// records the disagreement per frame and over the run. A few milliseconds a frame.
    #[arg(long)]
    pub keypoints: bool,
    /// Image mesh: grid spacing in pixels.
    #[arg(long, default_value_t = visage::MeshingOptions::default().spacing)]
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
    /// The morphable face model fitted to the landmarks: an ICT-FaceKit folder (its
    /// FaceXModel folder or a checkout); default: the compact model built into visage.
    #[arg(long, conflicts_with = "no_fit")]
    pub model: Option<PathBuf>,
    /// No morphable-model fit (no blendshapes, no identity).
    #[arg(long)]
    pub no_fit: bool,
    /// No progress bar and no closing line.
    #[arg(long)]
    pub quiet: bool,
}

/// Arguments of `visage run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    /// Output folder: sequence.pc2 with mesh.obj and mesh.mtl (every frame's surface),
    /// landmarks.json, metrics.json, camera.json (the intrinsics used), the blendshape
    /// curves; meshes/NNNNNN.ply with --ply.
    #[arg(long)]
    pub out: PathBuf,
    /// Also write a PLY per frame to OUT/meshes/.
    #[arg(long)]
    pub ply: bool,
    /// Also write the raw (unfused) surface on the same mesh to OUT/raw/ (PLY per frame).
    #[arg(long)]
    pub save_raw: bool,
    /// Write ASCII PLY instead of binary.
    #[arg(long)]
    pub ascii: bool,
    /// Replace a previous run in the output folder: its files are removed first (other files
    /// stay). Without it, a folder that is not empty is refused.
    #[arg(long)]
    pub overwrite: bool,
    /// Continue the run in the output folder where it stopped (killed, interrupted or failed):
    /// its files are cut back to the last frame they all hold and the run goes on after it,
    /// with the same input and options (checked; --max-frames may be raised). The temporal
    /// state is not saved: the last 300 kept frames are processed again, not written, to warm
    /// it up. A complete run is left as it is; an empty folder gets a new run. Not with
    /// --mode clip or --mesh image.
    #[arg(long, conflicts_with = "overwrite")]
    pub resume: bool,
    /// Which faces to mesh: the largest in view (a warning says when there were others), or
    /// every face of the first frame that shows one, each tracked on its own into OUT/face-N/
    /// (N from left to right) with OUT/faces.json listing them.
    #[arg(long, value_enum, default_value = "largest")]
    pub faces: FacesArg,
    #[command(flatten)]
    pub exports: ExportArgs,
}

/// `--faces`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FacesArg {
    /// The largest face in view.
    Largest,
    /// Every face of the first frame that shows one.
    All,
}

/// The help of `--lambda` and `--mu`, written from the defaults the pipeline takes for each
/// mesh and depth source, so that it cannot drift from them.
pub fn weight_help() -> (String, String) {
    use visage_fusion::MODEL_WEIGHTS_MAP as MODEL;
    use visage_fusion::{ANCHORED_WEIGHTS_FACE as FACE, ANCHORED_WEIGHTS_MAP as MAP};
    let image = visage_fem::Weights::default();
    (
        format!(
            "Smoothness weight λ (face and model meshes: mm⁴ of the template face, default {} \
             with the face or model depth, with depth maps {} on the face mesh and {} on the \
             model mesh; image mesh: reference pixels⁴, default {})",
            FACE.lambda, MAP.lambda, MODEL.lambda, image.lambda
        ),
        format!(
            "Temporal weight μ (dimensionless; default {} with the face or model depth, with \
             depth maps {} on the face mesh and {} on the model mesh; image mesh: default {})",
            FACE.mu, MAP.mu, MODEL.mu, image.mu
        ),
    )
}

/// Takes the output folder for this run: refuses one another process writes into, or one
/// that is not empty, or (with `--overwrite`) removes a previous run's files from it, saying
/// what it found; with `resume`, a run there is continued. The returned lock is held until
/// dropped.
pub(crate) fn claim_output_folder(
    out: &std::path::Path,
    overwrite: bool,
    resume: bool,
) -> anyhow::Result<visage::run_folder::FolderLock> {
    let claimed = visage::run_folder::claim(out, overwrite, resume)?;
    if let Some(cleared) = claimed.cleared {
        eprintln!("{}", cleared.describe(out));
    }
    Ok(claimed.lock)
}

impl PipelineArgs {
    /// The input's path: the video, folder or image, or the RGB-D recording.
    pub fn input_path(&self) -> &std::path::Path {
        match (&self.rgbd, &self.input) {
            (Some(dir), _) | (None, Some(dir)) => dir,
            (None, None) => unreachable!("clap requires the input or --rgbd"),
        }
    }

    /// The flags as the library's options.
    pub fn options(&self) -> PipelineOptions {
        PipelineOptions {
            rgbd: self.rgbd.is_some(),
            depth_scale: self.depth_scale,
            depth_intrinsics: self.depth_intrinsics.clone(),
            depth_to_color: self.depth_to_color.clone(),
            keep_depth_edges: self.keep_depth_edges,
            depth_config: self.depth_config.clone(),
            intrinsics: self.intrinsics.clone(),
            fov_deg: self.fov_deg,
            depth: self.depth.clone(),
            lambda: self.lambda,
            mu: self.mu,
            smoothing: self.smoothing.0,
            latency: self.latency,
            mesh: match self.mesh {
                MeshArg::Face => MeshKind::Face,
                MeshArg::Image => MeshKind::Image,
                MeshArg::Model => MeshKind::Model,
            },
            mode: match self.mode {
                ModeArg::Streaming => TemporalMode::Streaming,
                ModeArg::Clip => TemporalMode::Clip,
            },
            subdivision: self.subdivision,
            fair: self.fair,
            keypoints: self.keypoints,
            spacing: self.spacing,
            every: self.every,
            max_frames: self.max_frames,
            models: self.models.clone(),
            model: match (&self.model, self.no_fit) {
                (Some(dir), _) => ModelSource::IctFolder(dir.clone()),
                (None, true) => ModelSource::None,
                (None, false) => ModelSource::Embedded,
            },
        }
    }

    /// The input (frame selection applied) and a reconstructor set up for it, what they say
    /// printed (notices not with `--quiet`).
    pub fn open(&self) -> anyhow::Result<(Input, Reconstructor)> {
        let mut terminal = Terminal {
            bar: ProgressBar::hidden(),
            quiet: self.quiet,
        };
        Ok(self
            .options()
            .open(self.input_path(), FaceTarget::Largest, &mut terminal)?)
    }

    /// The progress bar for `input` (hidden with `--quiet`).
    pub fn progress(&self, input: &Input) -> ProgressBar {
        progress_bar(self.quiet, input.frames_to_process())
    }
}

impl RunArgs {
    /// The flags as the library's options.
    pub fn options(&self) -> RunOptions {
        RunOptions {
            pipeline: self.pipeline.options(),
            ply: self.ply,
            save_raw: self.save_raw,
            ascii: self.ascii,
            overwrite: self.overwrite,
            resume: self.resume,
            faces: match self.faces {
                FacesArg::Largest => Faces::Largest,
                FacesArg::All => Faces::All,
            },
            exports: self.exports.options(),
        }
    }
}

/// A run's progress on the terminal: the bar, warnings and notices, and each face's closing
/// lines (the results go to the output folder, not here).
struct Terminal {
    bar: ProgressBar,
    /// Notices are not printed (cautions are), and the bar is hidden.
    quiet: bool,
}

impl FrameSink for Terminal {
    fn frame_done(&mut self, _: &FrameMetrics) {
        self.bar.inc(1);
    }
    fn warning(&mut self, message: &str) {
        self.bar.suspend(|| eprintln!("warning: {message}"));
    }
    fn started(&mut self, frames: Option<usize>) {
        self.bar = progress_bar(self.quiet, frames);
    }
    fn notice(&mut self, message: &str) {
        if !self.quiet {
            self.bar.suspend(|| eprintln!("{message}"));
        }
    }
    fn caution(&mut self, message: &str) {
        self.bar.suspend(|| eprintln!("{message}"));
    }
    fn ended(&mut self) {
        self.bar.finish_and_clear();
    }
}

impl ClipProgress for Terminal {
    fn face_done(&mut self, face: &FaceRun) {
        let (Some(s), false) = (&face.run.summary, self.quiet) else {
            return;
        };
        let dir = &face.dir;
        if let Some(exports) = &face.exports {
            print_summary(dir, exports);
        }
        if let Some(point) = &face.run.resumed {
            eprint!(
                "resumed after frame {} ({} frames kept): ",
                point.after_frame, point.frames
            );
        }
        eprintln!(
            "{} frames ({} meshed, {} without a face) → {}; {:.1} fps, CPU {:.2}, \
             peak RSS {:.0} MiB; landmark jitter {:.3} px, {:.2}× steadier than tracked",
            s.frames,
            s.solved + s.carried,
            s.no_face,
            dir.display(),
            s.fps,
            s.cpu_use.unwrap_or(0.0),
            s.peak_rss_mib.unwrap_or(0.0),
            s.quality.image_jitter_px.fused.unwrap_or(0.0),
            s.quality.image_jitter_reduction.unwrap_or(0.0),
        );
    }
}

/// A progress bar and warnings for a run that keeps nothing (`visage bench`).
pub fn terminal(bar: &ProgressBar) -> impl FrameSink {
    Terminal {
        bar: bar.clone(),
        quiet: false,
    }
}

/// Runs `visage run`.
pub fn run(args: RunArgs) -> anyhow::Result<()> {
    let left = format!(
        "the files in {} keep the frames written so far, under temporary names ({}) where \
         unfinished; metrics.json says \"running\", and the same command with --resume goes on \
         after the last frame every file holds",
        args.out.display(),
        file_names::TMP_SUFFIX
    );
    run_with_stop(args, &interrupt::install(&left))
}

/// [`run`] that stops when `stop` turns true (Ctrl-C's flag, installed once per process).
pub fn run_with_stop(
    args: RunArgs,
    stop: &std::sync::Arc<std::sync::atomic::AtomicBool>,
) -> anyhow::Result<()> {
    let mut terminal = Terminal {
        bar: ProgressBar::hidden(),
        quiet: args.pipeline.quiet,
    };
    let input = args.pipeline.input_path();
    let run = visage::run_clip(input, &args.out, &args.options(), stop, &mut terminal);
    terminal.bar.finish_and_clear();
    run.map(|_| ()).map_err(with_exit_code)
}

/// `e` with the exit code it calls for: 130 for a run interrupted, 3 when no face was found,
/// else the code [`crate::exit::code_of`] gives it.
fn with_exit_code(e: visage::Error) -> anyhow::Error {
    let code = match &e {
        visage::Error::RunInterrupted { .. } => Some(interrupt::INTERRUPTED),
        visage::Error::NoFaceInInput { .. } => Some(crate::exit::NO_FACE),
        visage::Error::RunStopped { source, .. }
            if matches!(**source, visage::Error::NoFace { .. }) =>
        {
            Some(crate::exit::NO_FACE)
        }
        _ => None,
    };
    match code {
        Some(code) => Failure {
            code,
            error: e.into(),
        }
        .into(),
        None => e.into(),
    }
}
