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
    AlignedNetwork, BlendshapeFrame, Camera, DepthKind, DepthNetwork, DepthSequence, DepthSource,
    EdgeMask, FaceTarget, FrameMetrics, FrameSink, Input, Intrinsics, KeptFrames, LandmarksFrame,
    MeshFrame, MeshKind, ModelSource, NetworkConfig, OutputDir, PlyFormat, Reconstructor,
    Registration, ResumeState, RgbdLayout, RgbdOptions, RgbdRecording, RigidTransform,
    RunDescription, TemporalMode, DEFAULT_SUBDIVISION,
};

use std::sync::atomic::Ordering;

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
    /// Smoothness weight λ (face and model meshes: mm⁴ of the template face, default 1
    /// with the face or model depth, with depth maps 10 on the face mesh and 10³ on the
    /// model mesh; image mesh: reference pixels⁴, default 10).
    #[arg(long, allow_hyphen_values = true)]
    pub lambda: Option<f64>,
    /// Temporal weight μ (dimensionless; default 0.5; with depth maps 1 on the face
    /// mesh, 2 on the model mesh).
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

/// Refuses an output folder that is not empty, or (with `--overwrite`) removes a previous
/// run's files from it, saying what it found.
pub fn claim_output_folder(out: &std::path::Path, overwrite: bool) -> anyhow::Result<()> {
    let contents = visage::inspect_output_folder(out)?;
    if contents.is_empty() {
        return Ok(());
    }
    if !overwrite {
        return Err(Failure {
            code: crate::exit::BAD_INPUT,
            error: anyhow::anyhow!(
                "{}: the output folder is not empty; it holds {}. Pass --overwrite to replace \
                 a previous run's files (other files stay), or choose another folder",
                out.display(),
                contents.describe()
            ),
        }
        .into());
    }
    if contents.has_run() {
        let removed = visage::clear_outputs(out)?;
        eprintln!(
            "--overwrite: removed {} entries of the previous run from {} (it held {})",
            removed.len(),
            out.display(),
            contents.describe()
        );
    }
    Ok(())
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

/// The output folder with a progress bar and warnings on the terminal.
struct Terminal<'a, S> {
    sink: S,
    bar: &'a ProgressBar,
}

impl<S: FrameSink> FrameSink for Terminal<'_, S> {
    fn landmarks(&mut self, record: &LandmarksFrame) -> Result<(), visage::Error> {
        self.sink.landmarks(record)
    }
    fn mesh(&mut self, frame: &MeshFrame<'_>) -> Result<(), visage::Error> {
        self.sink.mesh(frame)
    }
    fn blendshapes(&mut self, frame: &BlendshapeFrame) -> Result<(), visage::Error> {
        self.sink.blendshapes(frame)
    }
    fn frame_done(&mut self, _: &FrameMetrics) {
        self.bar.inc(1);
    }
    fn warning(&mut self, message: &str) {
        self.bar.suspend(|| eprintln!("warning: {message}"));
    }
}

/// A progress bar and warnings for a sink that keeps nothing (`visage bench`).
pub fn terminal(bar: &ProgressBar) -> impl FrameSink + '_ {
    Terminal { sink: (), bar }
}

/// Runs `visage run`.
pub fn run(args: RunArgs) -> anyhow::Result<()> {
    run_with_stop(args, &interrupt::install())
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
    if !args.resume || !visage::inspect_output_folder(&args.out)?.has_run() {
        claim_output_folder(&args.out, args.overwrite)?;
    }
    // Ctrl-C ends the input: the frames read so far go through and are written.
    if args.faces == FacesArg::Largest {
        return run_face(&args, &args.out, FaceTarget::Largest, stop).map(|_| ());
    }
    let faces = first_faces(p)?;
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
        let folder = format!("{}{id}", visage::FACE_FOLDER_PREFIX);
        let dir = args.out.join(&folder);
        let result = run_face(&args, &dir, FaceTarget::Near(*bbox), stop);
        let (status, meshed) = match &result {
            Ok(meshed) => ("complete", *meshed),
            Err(_) => ("failed", 0),
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
        &args.out.join("faces.json"),
        &serde_json::json!({ "input": p.input_path().display().to_string(), "faces": records }),
    )?;
    first_error.map_or(Ok(()), Err)
}

/// The faces of the first frame that shows any, left to right: the frame's input index and
/// each face's box (`[x, y, width, height]`, pixels).
fn first_faces(p: &PipelineArgs) -> anyhow::Result<Vec<(usize, [f32; 4])>> {
    let models = p
        .models
        .clone()
        .unwrap_or_else(visage_face::model_files::models_dir);
    let mut mesh = visage_face::FaceMesh::load(&models)?;
    mesh.detectors = visage_face::DetectorUse::Both;
    let input = p.open_input()?;
    for frame in input {
        let frame = frame?;
        let mut boxes: Vec<[f32; 4]> = mesh
            .process(&frame.image)
            .with_context(|| format!("{}: face detection", frame.source))?
            .iter()
            .map(|f| f.bbox)
            .collect();
        if !boxes.is_empty() {
            boxes.sort_by(|a, b| a[0].total_cmp(&b[0]));
            return Ok(boxes.into_iter().map(|b| (frame.index, b)).collect());
        }
    }
    Ok(Vec::new())
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
    let (mut input, reconstructor) = p.open_for(target)?;
    let input_name = p.input_path().display().to_string();
    let selection = input.selection();
    let description = RunDescription {
        input: &input_name,
        intrinsics: reconstructor.intrinsics(),
        parameters: reconstructor.parameters(),
        selection,
    };
    let resume = match args.resume {
        true => visage::prepare_resume(dir, &description)?,
        false => ResumeState::Fresh,
    };
    let point = match resume {
        ResumeState::Fresh => None,
        ResumeState::Complete { frames } => {
            if !p.quiet {
                eprintln!(
                    "{}: the run there is complete ({frames} frames); nothing to resume",
                    dir.display()
                );
            }
            return Ok(meshed_in(dir));
        }
        ResumeState::Continue(point) => {
            if !p.quiet {
                eprintln!(
                    "--resume: {} frames of the previous run (status \"{}\") kept in {}; \
                     continuing after frame {} (warmed up on the {} frames before it){}",
                    point.frames,
                    point.previous_status,
                    dir.display(),
                    point.after_frame,
                    point.warm_up_frames,
                    match point.redone {
                        0 => String::new(),
                        1 => " (its last frame done again)".to_owned(),
                        n => format!(" (its last {n} frames done again)"),
                    }
                );
            }
            if let Some(index) = point.warm_up_after {
                input = input.after(index);
            }
            Some(point)
        }
    };
    // The frames the texture is fused from, kept as they are decoded (no second decode).
    let kept = KeptFrames::default();
    if args.exports.any() {
        let select = visage_export::texture_frames(input.frame_rate());
        input = input.keep_copies(select, kept.clone());
    }
    let format = if args.ascii {
        PlyFormat::Ascii
    } else {
        PlyFormat::BinaryLittleEndian
    };
    let mut out = OutputDir::create(dir)?;
    if let Some(point) = &point {
        out = out.resuming(point.clone());
    }
    out = out
        .with_ply(format, args.ply, args.save_raw)?
        .with_point_cache()?
        .with_landmarks()?;
    if !p.no_fit {
        out = out.with_blendshapes(input.frame_rate())?;
    }
    // The camera the meshes are in: `visage render MESH --intrinsics OUT/camera.json`.
    out.write_camera(reconstructor.intrinsics())?;
    out.write_running(&description)?;
    let bar = p.progress(&input);
    let input = input.stop_on(stop.clone());
    let mut sink = Terminal {
        sink: out,
        bar: &bar,
    };
    let mut outcome = reconstructor.run(input, &mut sink);
    if stop.load(Ordering::SeqCst) && outcome.error.is_none() {
        outcome.error = Some(visage::Error::Interrupted);
    }
    let s = &outcome.summary;
    if let (FaceTarget::Largest, true, Some(frame)) =
        (target, s.most_faces_seen > 1, s.most_faces_frame)
    {
        eprintln!(
            "warning: {} faces were in view (first in frame {frame}); only the largest was \
             meshed (--faces all meshes each)",
            s.most_faces_seen
        );
    }
    if outcome.error.is_none() && s.frames > 0 && s.solved + s.carried == 0 {
        outcome.error = Some(visage::Error::NoFace { frames: s.frames });
    }
    bar.finish_and_clear();
    let mut out = sink.sink;
    if let (Err(e), None) = (out.finish(), &outcome.error) {
        outcome.error = Some(e);
    }
    if let Some(identity) = &outcome.identity {
        // A failure here still leaves a metrics.json that says so.
        if let (Err(e), None) = (out.write_identity(identity), &outcome.error) {
            outcome.error = Some(e);
        }
    }
    let mut report = outcome.report(&input_name);
    report.selection = Some(selection);
    // The warm-up frames' records are the previous run's.
    let mut earlier_meshed = 0;
    if let Some(point) = &point {
        let warm_up = |f: &FrameMetrics| f.index <= point.after_frame;
        let warm_meshed = report.frames.iter().filter(|f| warm_up(f) && f.has_mesh());
        earlier_meshed = point.meshed.saturating_sub(warm_meshed.count());
        report.frames.retain(|f| !warm_up(f));
    }
    report.resumed = point.clone();
    out.write_metrics(&report)?;
    if let Some(visage::Error::Interrupted) = outcome.error {
        return Err(Failure {
            code: interrupt::INTERRUPTED,
            error: anyhow::anyhow!(
                "interrupted after {} frames: their meshes, landmarks.json and metrics.json \
                 (status \"interrupted\") are in {}; the same command with --resume goes \
                 on from there, `visage export {}` makes the other files",
                outcome.frames.len(),
                dir.display(),
                dir.display()
            ),
        }
        .into());
    }
    if let Some(e @ visage::Error::NoFace { .. }) = outcome.error {
        return Err(Failure {
            code: crate::exit::NO_FACE,
            error: anyhow::Error::new(e).context(format!(
                "{}: nothing to mesh (metrics.json is in {})",
                p.input_path().display(),
                dir.display()
            )),
        }
        .into());
    }
    if let Some(e) = outcome.error {
        return Err(anyhow::Error::new(e).context(format!(
            "stopped after {} frames (meshes so far and metrics.json are in {})",
            outcome.frames.len(),
            dir.display()
        )));
    }
    if args.exports.any() {
        let summary = exports_into(dir, &args.exports, Some(&kept.take()))?;
        if !p.quiet {
            print_summary(dir, &summary);
        }
    }
    if !p.quiet {
        let s = &outcome.summary;
        if let Some(point) = &point {
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
    Ok(earlier_meshed + outcome.summary.solved + outcome.summary.carried)
}

/// The frames a complete run in `dir` meshed, as its `metrics.json` says (0 when it does not).
fn meshed_in(dir: &std::path::Path) -> usize {
    let metrics = std::fs::read(dir.join("metrics.json"))
        .ok()
        .and_then(|bytes| serde_json::from_slice::<serde_json::Value>(&bytes).ok())
        .unwrap_or_default();
    let count = |key: &str| metrics["summary"][key].as_u64().unwrap_or(0) as usize;
    let earlier = metrics["resumed"]["meshed"].as_u64().unwrap_or(0) as usize;
    earlier + count("solved") + count("carried")
}
