//! `visage run`: a video, image folder or image in, a fused metric face mesh per frame out.
//!
//! Exit codes: 0 every frame processed; 2 bad input or environment — missing or unreadable
//! input, a video that breaks part-way (the readable frames are processed and written, the
//! message names the frame where decoding stopped), intrinsics for another image size, an
//! unwritable output folder, missing models; 1 an internal error. On any failure after the
//! output folder exists, `metrics.json` is still written, with `"status": "failed"` and the
//! error.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, ValueEnum};
use indicatif::ProgressBar;
use visage::{
    file_names, AlignedNetwork, Camera, DepthKind, DepthNetwork, DepthSequence, DepthSource,
    EdgeMask, FaceTarget, FolderOptions, FrameMetrics, FrameSink, Input, Intrinsics, KeptFrames,
    MeshKind, ModelSource, NetworkConfig, PlyFormat, Reconstructor, Registration, RgbdLayout,
    RgbdOptions, RgbdRecording, RigidTransform, TemporalMode, DEFAULT_SUBDIVISION,
};

use crate::commands::export::{exports_into, print_summary, ExportArgs};
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
        eprintln!(
            "--overwrite: removed {} entries of the previous run from {} (it held {})",
            cleared.removed.len(),
            out.display(),
            cleared.held
        );
    }
    Ok(claimed.lock)
}

impl PipelineArgs {
    /// The input (frame selection applied) and a reconstructor set up for it.
    pub fn open(&self) -> anyhow::Result<(Input, Reconstructor)> {
        self.open_for(FaceTarget::Largest)
    }

    /// The input's path: the video, folder or image, or the RGB-D recording.
    pub fn input_path(&self) -> &std::path::Path {
        match (&self.rgbd, &self.input) {
            (Some(dir), _) | (None, Some(dir)) => dir,
            (None, None) => unreachable!("clap requires the input or --rgbd"),
        }
    }

    /// The input, frame selection applied.
    pub fn open_input(&self) -> anyhow::Result<Input> {
        Ok(self.open_input_and_recording(None)?.0)
    }

    /// The input (frame selection applied) and, with --rgbd, its recording (`color`: the
    /// colour camera, for the registration).
    fn open_input_and_recording(
        &self,
        color: Option<Intrinsics>,
    ) -> anyhow::Result<(Input, Option<RgbdRecording>)> {
        let (mut input, recording) = match &self.rgbd {
            None => (Input::open(self.input_path())?, None),
            Some(dir) => {
                let recording = self.open_recording(dir, color)?;
                let paths: Vec<PathBuf> =
                    recording.frames.iter().map(|f| f.color.clone()).collect();
                let times: Option<Vec<f64>> = recording.frames.iter().map(|f| f.time_s).collect();
                let input = match times {
                    Some(times) => Input::timed_images(dir, paths, times, recording.frame_rate())?,
                    // Untimed folder pairs go in name order, as rgb/ lists them.
                    None => Input::open(&dir.join("rgb"))?,
                };
                (input, Some(recording))
            }
        };
        input = input.every(self.every)?;
        if let Some(m) = self.max_frames {
            input = input.max_frames(m)?;
        }
        Ok((input, recording))
    }

    /// The RGB-D recording in `dir`, registered to `color` when --depth-intrinsics is given.
    fn open_recording(
        &self,
        dir: &std::path::Path,
        color: Option<Intrinsics>,
    ) -> anyhow::Result<RgbdRecording> {
        let registration = match (&self.depth_intrinsics, color) {
            (Some(path), Some(color)) => Some(Registration {
                depth: Intrinsics::load_json(path)?,
                color,
                depth_to_color: match &self.depth_to_color {
                    Some(t) => RigidTransform::load_json(t)?,
                    None => RigidTransform::IDENTITY,
                },
            }),
            _ => None,
        };
        let options = RgbdOptions {
            depth_scale: self.depth_scale,
            registration,
            edges: (!self.keep_depth_edges).then(EdgeMask::default),
            ..RgbdOptions::default()
        };
        let recording = RgbdRecording::open(dir, &options).context("cannot use --rgbd")?;
        if !self.quiet {
            eprintln!(
                "{}: {} recording, {} colour frames, {} with a depth map within {:.0} ms{}",
                dir.display(),
                match recording.layout {
                    RgbdLayout::Tum => "TUM RGB-D",
                    RgbdLayout::Folders => "rgb/ + depth/",
                },
                recording.frames.len(),
                recording.associated(),
                options.max_time_difference_s * 1e3,
                match recording.unmatched_depth {
                    0 => String::new(),
                    n => format!(" ({n} depth maps matched no colour frame)"),
                }
            );
        }
        Ok(recording)
    }

    /// [`PipelineArgs::open`] for a run that follows `target`.
    pub fn open_for(&self, target: FaceTarget) -> anyhow::Result<(Input, Reconstructor)> {
        let given = self
            .intrinsics
            .as_ref()
            .map(|path| Intrinsics::load_json(path))
            .transpose()?;
        let (input, recording) = self.open_input_and_recording(given)?;
        let camera = match (&self.intrinsics, self.fov_deg) {
            (Some(path), _) => {
                let k = given.expect("loaded above");
                let (w, h) = input.size();
                k.check_size(w, h).with_context(|| {
                    format!(
                        "{}: intrinsics are for another image size than {} ({w}×{h})",
                        path.display(),
                        self.input_path().display()
                    )
                })?;
                Camera::Intrinsics(k)
            }
            (None, Some(fov)) => Camera::FovDeg(fov),
            (None, None)
                if recording
                    .as_ref()
                    .is_some_and(|r| r.layout == RgbdLayout::Tum)
                    && input.size() == (640, 480) =>
            {
                eprintln!(
                    "intrinsics: the TUM RGB-D default camera (fx = fy = 525, cx = 319.5, \
                     cy = 239.5; the freiburg calibrations differ by up to 1.5 %); pass \
                     --intrinsics for yours"
                );
                Camera::Intrinsics(Intrinsics::new(640, 480, 525.0, 525.0, 319.5, 239.5)?)
            }
            (None, None) => {
                if let Some((path, f35)) = input.exif_focal_35mm() {
                    eprintln!(
                        "intrinsics: {f35} mm (35 mm equivalent) from the EXIF of {}",
                        path.display()
                    );
                }
                Camera::Auto
            }
        };
        let depth = match (recording, self.depth.as_str()) {
            (Some(recording), _) => DepthSource::maps(recording),
            (None, "face") => DepthSource::Face,
            (None, "model") => DepthSource::Model,
            (None, network) if network.to_ascii_lowercase().ends_with(".onnx") => {
                let config = self
                    .depth_config
                    .as_ref()
                    .map(|path| NetworkConfig::load(path))
                    .transpose()?;
                let net =
                    DepthNetwork::load(network.as_ref(), config).context("cannot use --depth")?;
                if !self.quiet {
                    let (iw, ih) = net.input_size();
                    let (ow, oh) = net.output_size();
                    let c = net.config();
                    eprintln!(
                        "depth network {network}: {iw}×{ih} in, {ow}×{oh} {} out, on the {}, \
                         aligned {}",
                        format!("{:?}", c.output.kind).to_lowercase(),
                        match c.region {
                            visage::NetworkRegion::Face => "face",
                            visage::NetworkRegion::Frame => "whole frame",
                        },
                        match c.alignment() {
                            visage::AlignMode::None => "not at all (metric)",
                            visage::AlignMode::Scale => "by a scale per frame",
                            _ => "by a scale and shift per frame",
                        }
                    );
                }
                DepthSource::maps(AlignedNetwork::new(net))
            }
            (None, dir) => DepthSource::maps(
                DepthSequence::open(
                    dir.as_ref(),
                    self.depth_scale.unwrap_or(1000.0),
                    DepthKind::Z,
                )
                .context("cannot use --depth")?,
            ),
        };
        let mut builder = Reconstructor::builder()
            .camera(camera)
            .depth(depth)
            .mesh(match self.mesh {
                MeshArg::Face => MeshKind::Face,
                MeshArg::Image => MeshKind::Image,
                MeshArg::Model => MeshKind::Model,
            })
            .mode(match self.mode {
                ModeArg::Streaming => TemporalMode::Streaming,
                ModeArg::Clip => TemporalMode::Clip,
            })
            .subdivision(self.subdivision)
            .spacing(self.spacing);
        builder = builder
            .landmark_smoothing(self.smoothing.0)
            .latency(self.latency)
            .fairing(self.fair)
            .keypoint_motion(self.keypoints)
            .face_target(target);
        if let Some(lambda) = self.lambda {
            builder = builder.lambda(lambda);
        }
        if let Some(mu) = self.mu {
            builder = builder.mu(mu);
        }
        if let Some(dir) = &self.models {
            builder = builder.models_dir(dir);
        }
        if let Some(dir) = &self.model {
            builder = builder.model(ModelSource::IctFolder(dir.clone()));
        } else if self.no_fit {
            builder = builder.model(ModelSource::None);
        }
        let reconstructor = builder.build_for(&input)?;
        Ok((input, reconstructor))
    }

    /// The progress bar for `input` (hidden with `--quiet`).
    pub fn progress(&self, input: &Input) -> ProgressBar {
        progress_bar(self.quiet, input.frames_to_process())
    }
}

/// A run's progress on the terminal: the bar, warnings and notices (the results go to the
/// output folder, not here).
struct Terminal {
    bar: ProgressBar,
    /// Notices are not printed, and the bar is hidden.
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
    let p = &args.pipeline;
    std::fs::metadata(p.input_path())
        .with_context(|| format!("{}: cannot read the input", p.input_path().display()))?;
    // With --resume, a previous run is continued rather than refused.
    let _lock = claim_output_folder(&args.out, args.overwrite, args.resume)?;
    // Ctrl-C ends the input: the frames read so far go through and are written.
    if args.faces == FacesArg::Largest {
        return run_face(&args, &args.out, FaceTarget::Largest, stop).map(|_| ());
    }
    let models = p
        .models
        .clone()
        .unwrap_or_else(visage_face::model_files::models_dir);
    let faces = visage::first_faces(p.open_input()?, &models)?;
    if faces.is_empty() {
        return Err(Failure {
            code: crate::exit::NO_FACE,
            error: anyhow::anyhow!(
                "{}: no face was found in any frame",
                p.input_path().display()
            ),
        }
        .into());
    }
    if !p.quiet {
        eprintln!(
            "{} face{} in frame {}: each is tracked into its own folder",
            faces.len(),
            if faces.len() == 1 { "" } else { "s" },
            faces[0].0
        );
    }
    let mut records = Vec::new();
    let mut first_error = None;
    for (id, (frame, bbox)) in (1..).zip(&faces) {
        let folder = format!("{}{id}", file_names::FACE_FOLDER_PREFIX);
        let dir = args.out.join(&folder);
        let result = run_face(&args, &dir, FaceTarget::Near(*bbox), stop);
        let (status, meshed) = match &result {
            Ok(meshed) => ("complete".to_owned(), *meshed),
            Err(_) => ended_as(&dir),
        };
        records.push(serde_json::json!({
            "id": id,
            "folder": folder,
            "first_frame": frame,
            "bbox": bbox,
            "status": status,
            "frames_meshed": meshed,
        }));
        if let Err(e) = result {
            let interrupted = e
                .downcast_ref::<Failure>()
                .is_some_and(|f| f.code == interrupt::INTERRUPTED);
            first_error.get_or_insert(e);
            if interrupted {
                break;
            }
        }
    }
    visage::write_json_atomically(
        &args.out.join(file_names::FACES),
        &serde_json::json!({ "input": p.input_path().display().to_string(), "faces": records }),
    )?;
    first_error.map_or(Ok(()), Err)
}

/// How the run in `dir` ended, as its metrics.json says (`"failed"` when it has none): its
/// status and the frames it meshed.
fn ended_as(dir: &std::path::Path) -> (String, usize) {
    let m = std::fs::read(dir.join(file_names::METRICS))
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .unwrap_or_default();
    let count = |v: &serde_json::Value| v.as_u64().unwrap_or(0) as usize;
    let meshed = count(&m["summary"]["solved"])
        + count(&m["summary"]["carried"])
        + count(&m["resumed"]["meshed"]);
    let status = m["status"].as_str().unwrap_or("failed").to_owned();
    (status, meshed)
}

/// One tracked face's run into `dir` (continued with `--resume`): the frames meshed, or the
/// error (exit code attached).
fn run_face(
    args: &RunArgs,
    dir: &std::path::Path,
    target: FaceTarget,
    stop: &std::sync::Arc<std::sync::atomic::AtomicBool>,
) -> anyhow::Result<usize> {
    let p = &args.pipeline;
    let (input, reconstructor) = p.open_for(target)?;
    // The frames the texture is fused from, kept as they are decoded (no second decode).
    let kept = KeptFrames::default();
    let keep = args.exports.any().then(|| {
        let select: visage::FrameFilter =
            Box::new(visage_export::texture_frames(input.frame_rate()));
        (select, kept.clone())
    });
    let format = if args.ascii {
        PlyFormat::Ascii
    } else {
        PlyFormat::BinaryLittleEndian
    };
    let options = FolderOptions {
        input_name: p.input_path().display().to_string(),
        input_file: visage::run_folder::InputFile::of(p.input_path())?,
        resume: args.resume,
        ply: (format, args.ply, args.save_raw),
        blendshapes: !p.no_fit,
        keep,
        stop: Some(stop.clone()),
        target,
    };
    let mut progress = Terminal {
        bar: ProgressBar::hidden(),
        quiet: p.quiet,
    };
    // What the closing message advises: going on with --resume, or why this run cannot.
    let go_on = match visage::run_folder::RunParameters::cannot_resume(reconstructor.parameters()) {
        None => "the same command with --resume goes on from there".to_owned(),
        Some(reason) => format!("it cannot be resumed: {reason}"),
    };
    let run = visage::run_into(input, reconstructor, dir, options, &mut progress);
    progress.bar.finish_and_clear();
    let run = run?;
    let Some(s) = &run.summary else {
        return Ok(run.meshed);
    };
    match run.error {
        Some(visage::Error::Interrupted) => {
            return Err(Failure {
                code: interrupt::INTERRUPTED,
                error: anyhow::anyhow!(
                    "interrupted after {} frames: their meshes, {} and {} \
                     (status \"interrupted\") are in {}; `visage export {}` makes the other \
                     files; {go_on}",
                    run.frames,
                    file_names::LANDMARKS,
                    file_names::METRICS,
                    dir.display(),
                    dir.display()
                ),
            }
            .into())
        }
        Some(e @ visage::Error::NoFace { .. }) => {
            return Err(Failure {
                code: crate::exit::NO_FACE,
                error: anyhow::Error::new(e).context(format!(
                    "{}: nothing to mesh ({} is in {})",
                    p.input_path().display(),
                    file_names::METRICS,
                    dir.display()
                )),
            }
            .into())
        }
        Some(e) => {
            let kept = if run.finished {
                format!(
                    "stopped after {} frame{}: the files in {} hold {} frame{}",
                    run.frames,
                    if run.frames == 1 { "" } else { "s" },
                    dir.display(),
                    run.kept,
                    if run.kept == 1 { "" } else { "s" },
                )
            } else {
                format!(
                    "stopped after {} frame{}: what was written of them stays in {} under \
                     temporary names ({})",
                    run.frames,
                    if run.frames == 1 { "" } else { "s" },
                    dir.display(),
                    file_names::TMP_SUFFIX
                )
            };
            let context = match &run.metrics_error {
                None => format!(
                    "{kept}, and {} says \"failed\"; {go_on}",
                    file_names::METRICS
                ),
                Some(m) => format!(
                    "{kept}, but {} could not be written either ({}); once the cause is \
                     fixed, the same command with --resume goes on from there",
                    file_names::METRICS,
                    with_causes(m)
                ),
            };
            return Err(anyhow::Error::new(e).context(context));
        }
        None => {}
    }
    if args.exports.any() {
        let summary = exports_into(dir, &args.exports, Some(&kept.take()))?;
        if !p.quiet {
            print_summary(dir, &summary);
        }
    }
    if !p.quiet {
        if let Some(point) = &run.resumed {
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
    Ok(run.meshed)
}

/// `error` and its causes, as one line.
fn with_causes(error: &dyn std::error::Error) -> String {
    std::iter::successors(Some(error), |e| e.source())
        .map(|e| e.to_string())
        .collect::<Vec<_>>()
        .join(": ")
}
