//! `visage.run`: a clip run into a folder as `visage run INPUT --out OUT` does it — the same
//! options (named like the flags, snake_case), the same files, the same error messages — with
//! the frames done reported to a Python callable. The GIL is released while the run works and
//! taken only to call back.
//!
//! Not here: `--rgbd` and its flags, `--faces all`, and the exports (`--glb`, `--texture`,
//! `--plots`, `--report`, `--preview`), which `visage export OUT` makes from the folder.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use visage::{
    error_chain, file_names, Camera, DepthKind, DepthNetwork, DepthSequence, DepthSource,
    FaceTarget, FolderOptions, FrameMetrics, FrameSink, Input, Intrinsics, MeshKind, ModelSource,
    NetworkConfig, PlyFormat, Reconstructor, TemporalMode, DEFAULT_SUBDIVISION,
};

use crate::error::error;

/// `visage run`'s options, as the Python call names them (`None`: the flag's default).
struct RunOptions {
    intrinsics: Option<PathBuf>,
    fov_deg: Option<f64>,
    depth: Option<String>,
    depth_config: Option<PathBuf>,
    depth_scale: Option<f64>,
    lambda: Option<f64>,
    mu: Option<f64>,
    /// `Some(None)`: `--smoothing off`.
    smoothing: Option<Option<f64>>,
    latency: Option<usize>,
    mesh: Option<String>,
    mode: Option<String>,
    subdivision: Option<usize>,
    fair: Option<f64>,
    keypoints: bool,
    spacing: Option<u32>,
    every: Option<usize>,
    max_frames: Option<usize>,
    models: Option<PathBuf>,
    model: Option<PathBuf>,
    no_fit: bool,
    ply: bool,
    save_raw: bool,
    ascii: bool,
    overwrite: bool,
    resume: bool,
}

/// `value`, when given, is one of `choices` (as clap checks `--flag`'s), else a `ValueError`
/// that lists them.
fn choice(name: &str, value: &Option<String>, choices: &[&str]) -> PyResult<()> {
    match value.as_deref() {
        Some(v) if !choices.contains(&v) => Err(PyValueError::new_err(format!(
            "{name}={v:?}: must be one of {}",
            choices
                .iter()
                .map(|c| format!("{c:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        ))),
        _ => Ok(()),
    }
}

impl RunOptions {
    /// The input (frame selection applied) and the reconstructor for it, as
    /// `PipelineArgs::open_for` in the command line makes them (its messages included).
    fn open(&self, input: &Path) -> Result<(Input, Reconstructor), String> {
        let given = self
            .intrinsics
            .as_ref()
            .map(|path| Intrinsics::load_json(path))
            .transpose()
            .map_err(|e| error_chain(&e))?;
        let mut opened = Input::open(input).map_err(|e| error_chain(&e))?;
        opened = opened
            .every(self.every.unwrap_or(1))
            .map_err(|e| error_chain(&e))?;
        if let Some(m) = self.max_frames {
            opened = opened.max_frames(m).map_err(|e| error_chain(&e))?;
        }
        let camera = match (&self.intrinsics, given, self.fov_deg) {
            (Some(path), Some(k), _) => {
                let (w, h) = opened.size();
                k.check_size(w, h).map_err(|e| {
                    format!(
                        "{}: intrinsics are for another image size than {} ({w}×{h}): {}",
                        path.display(),
                        input.display(),
                        error_chain(&e)
                    )
                })?;
                Camera::Intrinsics(k)
            }
            (_, _, Some(fov)) => Camera::FovDeg(fov),
            _ => Camera::Auto,
        };
        let depth = match self.depth.as_deref().unwrap_or("face") {
            "face" => DepthSource::Face,
            "model" => DepthSource::Model,
            network if network.to_ascii_lowercase().ends_with(".onnx") => {
                let config = self
                    .depth_config
                    .as_ref()
                    .map(|path| NetworkConfig::load(path))
                    .transpose()
                    .map_err(|e| error_chain(&e))?;
                let net = DepthNetwork::load(network.as_ref(), config)
                    .map_err(|e| format!("cannot use --depth: {}", error_chain(&e)))?;
                DepthSource::maps(visage::AlignedNetwork::new(net))
            }
            dir => DepthSource::maps(
                DepthSequence::open(
                    dir.as_ref(),
                    self.depth_scale.unwrap_or(1000.0),
                    DepthKind::Z,
                )
                .map_err(|e| format!("cannot use --depth: {}", error_chain(&e)))?,
            ),
        };
        let mut builder = Reconstructor::builder()
            .camera(camera)
            .depth(depth)
            .mesh(match self.mesh.as_deref() {
                Some("image") => MeshKind::Image,
                Some("model") => MeshKind::Model,
                _ => MeshKind::Face,
            })
            .mode(match self.mode.as_deref() {
                Some("clip") => TemporalMode::Clip,
                _ => TemporalMode::Streaming,
            })
            .subdivision(self.subdivision.unwrap_or(DEFAULT_SUBDIVISION))
            .spacing(
                self.spacing
                    .unwrap_or(visage::MeshingOptions::default().spacing),
            )
            .landmark_smoothing(
                self.smoothing
                    .unwrap_or(Some(visage::DEFAULT_LANDMARK_SMOOTHING)),
            )
            .latency(self.latency.unwrap_or(visage::DEFAULT_LATENCY_FRAMES))
            .fairing(self.fair)
            .keypoint_motion(self.keypoints)
            .face_target(FaceTarget::Largest);
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
        let reconstructor = builder.build_for(&opened).map_err(|e| error_chain(&e))?;
        Ok((opened, reconstructor))
    }

    /// The choices and combinations the command line's parser checks.
    fn check(&self) -> PyResult<()> {
        choice("mesh", &self.mesh, &["face", "image", "model"])?;
        choice("mode", &self.mode, &["streaming", "clip"])?;
        let conflicts = [
            (
                self.intrinsics.is_some() && self.fov_deg.is_some(),
                "intrinsics and fov_deg",
            ),
            (self.model.is_some() && self.no_fit, "model and no_fit"),
            (self.overwrite && self.resume, "overwrite and resume"),
        ];
        for (both, names) in conflicts {
            if both {
                return Err(PyValueError::new_err(format!(
                    "{names} cannot be given together"
                )));
            }
        }
        Ok(())
    }
}

/// Tells Python of the run's frames (the progress callable, with the GIL taken for it) and
/// stops the run on Ctrl-C or when the callable raises; the warnings and notices go to
/// `notify(kind, message)`.
struct PythonProgress {
    progress: Option<Py<PyAny>>,
    notify: Py<PyAny>,
    done: usize,
    total: Option<usize>,
    stop: Arc<AtomicBool>,
    /// The first Python error (a raising callable, Ctrl-C): raised after the run.
    raised: Option<PyErr>,
}

impl PythonProgress {
    /// `f` with the GIL taken, after a look for Ctrl-C; nothing once Python raised.
    fn call(&mut self, f: impl FnOnce(Python<'_>, &Self) -> PyResult<()>) {
        if self.raised.is_some() {
            return;
        }
        let this = &*self;
        if let Err(e) = Python::attach(|py| py.check_signals().and_then(|()| f(py, this))) {
            self.raised = Some(e);
            self.stop.store(true, Ordering::SeqCst);
        }
    }

    fn tell(&mut self, kind: &'static str, message: &str) {
        self.call(|py, this| this.notify.call1(py, (kind, message)).map(|_| ()));
    }
}

impl FrameSink for PythonProgress {
    fn started(&mut self, frames: Option<usize>) {
        self.total = frames;
    }

    fn frame_done(&mut self, _: &FrameMetrics) {
        self.done += 1;
        let (done, total) = (self.done, self.total);
        self.call(|py, this| match &this.progress {
            Some(f) => f.call1(py, (done, total)).map(|_| ()),
            None => Ok(()),
        });
    }

    fn warning(&mut self, message: &str) {
        self.tell("warning", message);
    }

    fn notice(&mut self, message: &str) {
        self.tell("notice", message);
    }
}

/// What a run did, for Python: `frames` processed, `meshed`, `kept` in the folder, and the
/// summary as `metrics.json` has it (`None` when a resume found the run complete).
type RunReport = (usize, usize, usize, Option<String>);

/// `--smoothing`'s value: a positive number or `off` (`Some(None)`).
fn smoothing(value: Option<String>) -> PyResult<Option<Option<f64>>> {
    let Some(s) = value else {
        return Ok(None);
    };
    if s == "off" {
        return Ok(Some(None));
    }
    match s.parse::<f64>() {
        Ok(r) if r.is_finite() && r > 0.0 => Ok(Some(Some(r))),
        _ => Err(PyValueError::new_err(format!(
            "smoothing={s}: neither a positive number nor \"off\""
        ))),
    }
}

/// `visage run INPUT --out OUT [options]`; see the package's `visage.run`. `notify(kind,
/// message)` is told the warnings (`"warning"`) and notices (`"notice"`) the command line
/// prints; `smoothing` comes as text (a number or `off`). Returns `frames`, `meshed`, `kept`
/// and `summary_json` (`metrics.json`'s summary).
#[pyfunction]
#[pyo3(signature = (input, out_dir, notify, progress=None, *, intrinsics=None, fov_deg=None,
    depth=None, depth_config=None, depth_scale=None, lambda_=None, mu=None, smoothing=None,
    latency=None, mesh=None, mode=None, subdivision=None, fair=None, keypoints=false,
    spacing=None, every=None, max_frames=None, models=None, model=None, no_fit=false,
    ply=false, save_raw=false, ascii=false, overwrite=false, resume=false))]
#[allow(clippy::too_many_arguments)]
pub fn run(
    py: Python<'_>,
    input: PathBuf,
    out_dir: PathBuf,
    notify: Py<PyAny>,
    progress: Option<Py<PyAny>>,
    intrinsics: Option<PathBuf>,
    fov_deg: Option<f64>,
    depth: Option<String>,
    depth_config: Option<PathBuf>,
    depth_scale: Option<f64>,
    lambda_: Option<f64>,
    mu: Option<f64>,
    smoothing: Option<String>,
    latency: Option<usize>,
    mesh: Option<String>,
    mode: Option<String>,
    subdivision: Option<usize>,
    fair: Option<f64>,
    keypoints: bool,
    spacing: Option<u32>,
    every: Option<usize>,
    max_frames: Option<usize>,
    models: Option<PathBuf>,
    model: Option<PathBuf>,
    no_fit: bool,
    ply: bool,
    save_raw: bool,
    ascii: bool,
    overwrite: bool,
    resume: bool,
) -> PyResult<Py<PyDict>> {
    let options = RunOptions {
        intrinsics,
        fov_deg,
        depth,
        depth_config,
        depth_scale,
        lambda: lambda_,
        mu,
        smoothing: self::smoothing(smoothing)?,
        latency,
        mesh,
        mode,
        subdivision,
        fair,
        keypoints,
        spacing,
        every,
        max_frames,
        models,
        model,
        no_fit,
        ply,
        save_raw,
        ascii,
        overwrite,
        resume,
    };
    options.check()?;
    let out = out_dir;
    let stop = Arc::new(AtomicBool::new(false));
    let mut sink = PythonProgress {
        progress,
        notify,
        done: 0,
        total: None,
        stop: stop.clone(),
        raised: None,
    };
    let outcome = py.detach(|| run_folder(&input, &out, &options, &stop, &mut sink));
    if let Some(e) = sink.raised {
        return Err(e);
    }
    let (frames, meshed, kept, summary) = outcome.map_err(error)?;
    let d = PyDict::new(py);
    d.set_item("frames", frames)?;
    d.set_item("meshed", meshed)?;
    d.set_item("kept", kept)?;
    d.set_item("summary_json", summary)?;
    Ok(d.unbind())
}

/// The run itself (no GIL): what `run_with_stop` and `run_face` do in the command line for
/// the largest face, the same messages for the same failures.
fn run_folder(
    input: &Path,
    out: &Path,
    options: &RunOptions,
    stop: &Arc<AtomicBool>,
    sink: &mut PythonProgress,
) -> Result<RunReport, String> {
    std::fs::metadata(input).map_err(|e| {
        format!(
            "{}: cannot read the input: {}",
            input.display(),
            error_chain(&e)
        )
    })?;
    let claimed = visage::run_folder::claim(out, options.overwrite, options.resume)
        .map_err(|e| error_chain(&e))?;
    if let Some(cleared) = &claimed.cleared {
        sink.notice(&format!(
            "--overwrite: removed {} entries of the previous run from {} (it held {})",
            cleared.removed.len(),
            out.display(),
            cleared.held
        ));
    }
    let (opened, reconstructor) = options.open(input)?;
    let format = if options.ascii {
        PlyFormat::Ascii
    } else {
        PlyFormat::BinaryLittleEndian
    };
    let folder = FolderOptions {
        input_name: input.display().to_string(),
        input_file: visage::run_folder::InputFile::of(input).map_err(|e| error_chain(&e))?,
        resume: options.resume,
        ply: (format, options.ply, options.save_raw),
        blendshapes: !options.no_fit,
        keep: None,
        stop: Some(stop.clone()),
        target: FaceTarget::Largest,
    };
    let go_on = match visage::run_folder::RunParameters::cannot_resume(reconstructor.parameters()) {
        None => "the same command with --resume goes on from there".to_owned(),
        Some(reason) => format!("it cannot be resumed: {reason}"),
    };
    let run =
        visage::run_into(opened, reconstructor, out, folder, sink).map_err(|e| error_chain(&e))?;
    let summary = run
        .summary
        .as_ref()
        .map(|s| serde_json::to_string(s).unwrap_or_default());
    let Some(e) = run.error else {
        return Ok((run.frames, run.meshed, run.kept, summary));
    };
    let plural = |n: usize| if n == 1 { "" } else { "s" };
    Err(match e {
        visage::Error::Interrupted => format!(
            "interrupted after {} frames: their meshes, {} and {} (status \"interrupted\") are \
             in {}; `visage export {}` makes the other files; {go_on}",
            run.frames,
            file_names::LANDMARKS,
            file_names::METRICS,
            out.display(),
            out.display()
        ),
        e @ visage::Error::NoFace { .. } => format!(
            "{}: nothing to mesh ({} is in {}): {}",
            input.display(),
            file_names::METRICS,
            out.display(),
            error_chain(&e)
        ),
        e => {
            let kept = if run.finished {
                format!(
                    "stopped after {} frame{}: the files in {} hold {} frame{}",
                    run.frames,
                    plural(run.frames),
                    out.display(),
                    run.kept,
                    plural(run.kept),
                )
            } else {
                format!(
                    "stopped after {} frame{}: what was written of them stays in {} under \
                     temporary names ({})",
                    run.frames,
                    plural(run.frames),
                    out.display(),
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
                    error_chain(m)
                ),
            };
            format!("{context}: {}", error_chain(&e))
        }
    })
}
