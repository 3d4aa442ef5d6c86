//! `visage.run`: `visage run INPUT --out OUT` as a call. Its options, named like the flags
//! (snake_case), fill the library's `RunOptions` as the command line's flags do, and
//! `visage::run_clip` runs them as it runs the command line's: the same files, exports
//! included, and the same error messages. The frames done are reported to a Python callable;
//! the GIL is released while the run works and taken only to call back.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use visage::{
    ClipProgress, Faces, FrameMetrics, FrameSink, MeshKind, ModelSource, RunOptions, TemporalMode,
};

use crate::error::error;

/// `value`, when given, is one of `choices` (as clap checks `--flag`'s), else a `ValueError`
/// that lists them.
fn choice<'a>(name: &str, value: Option<&'a str>, choices: &[&str]) -> PyResult<Option<&'a str>> {
    match value {
        Some(v) if !choices.contains(&v) => Err(PyValueError::new_err(format!(
            "{name}={v:?}: must be one of {}",
            choices
                .iter()
                .map(|c| format!("{c:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        ))),
        v => Ok(v),
    }
}

/// The combinations the command line's parser refuses: options given together that conflict,
/// or one given without another it needs.
fn check_combinations(given: &[(&str, bool)]) -> PyResult<()> {
    let on = |name: &str| given.iter().any(|&(n, g)| n == name && g);
    let conflicts = [
        ("input", "rgbd"),
        ("rgbd", "depth"),
        ("intrinsics", "fov_deg"),
        ("model", "no_fit"),
        ("overwrite", "resume"),
    ];
    for (a, b) in conflicts {
        if on(a) && on(b) {
            return Err(PyValueError::new_err(format!(
                "{a} and {b} cannot be given together"
            )));
        }
    }
    let needs = [
        ("depth_intrinsics", "rgbd"),
        ("depth_intrinsics", "intrinsics"),
        ("depth_to_color", "depth_intrinsics"),
        ("keep_depth_edges", "rgbd"),
    ];
    for (a, b) in needs {
        if on(a) && !on(b) {
            return Err(PyValueError::new_err(format!("{a} needs {b}")));
        }
    }
    Ok(())
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

/// The faces' runs come back as the call's result: nothing more to tell.
impl ClipProgress for PythonProgress {}

impl FrameSink for PythonProgress {
    fn started(&mut self, frames: Option<usize>) {
        self.done = 0;
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

/// `visage run INPUT --out OUT [options]`; see the package's `visage.run`. `input` is `None`
/// with `rgbd` (the recording is the input). `notify(kind, message)` is told the warnings
/// (`"warning"`) and notices (`"notice"`) the command line prints; `smoothing` comes as text
/// (a number or `off`). Returns a dict per face run (one, or with `faces="all"` each face's):
/// its folder `dir`, `frames`, `meshed`, `kept`, `summary_json` (`metrics.json`'s summary) and
/// `exports_json` (`export.json`'s contents, when exports were made).
#[pyfunction]
#[pyo3(signature = (input, out_dir, notify, progress=None, *, rgbd=None, depth_scale=None,
    depth_intrinsics=None, depth_to_color=None, keep_depth_edges=false, depth_config=None,
    intrinsics=None, fov_deg=None, depth=None, lambda_=None, mu=None, smoothing=None,
    latency=None, mesh=None, mode=None, subdivision=None, fair=None, keypoints=false,
    spacing=None, every=None, max_frames=None, models=None, model=None, no_fit=false,
    ply=false, save_raw=false, ascii=false, overwrite=false, resume=false, faces=None,
    glb=false, texture=false, plots=false, report=false, preview=false))]
#[allow(clippy::too_many_arguments)]
pub fn run<'py>(
    py: Python<'py>,
    input: Option<PathBuf>,
    out_dir: PathBuf,
    notify: Py<PyAny>,
    progress: Option<Py<PyAny>>,
    rgbd: Option<PathBuf>,
    depth_scale: Option<f64>,
    depth_intrinsics: Option<PathBuf>,
    depth_to_color: Option<PathBuf>,
    keep_depth_edges: bool,
    depth_config: Option<PathBuf>,
    intrinsics: Option<PathBuf>,
    fov_deg: Option<f64>,
    depth: Option<String>,
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
    faces: Option<String>,
    glb: bool,
    texture: bool,
    plots: bool,
    report: bool,
    preview: bool,
) -> PyResult<Bound<'py, PyList>> {
    let mesh = choice("mesh", mesh.as_deref(), &["face", "image", "model"])?;
    let mode = choice("mode", mode.as_deref(), &["streaming", "clip"])?;
    let faces = choice("faces", faces.as_deref(), &["largest", "all"])?;
    let smoothing = self::smoothing(smoothing)?;
    check_combinations(&[
        ("input", input.is_some()),
        ("rgbd", rgbd.is_some()),
        ("depth", depth.is_some()),
        ("depth_intrinsics", depth_intrinsics.is_some()),
        ("depth_to_color", depth_to_color.is_some()),
        ("keep_depth_edges", keep_depth_edges),
        ("intrinsics", intrinsics.is_some()),
        ("fov_deg", fov_deg.is_some()),
        ("model", model.is_some()),
        ("no_fit", no_fit),
        ("overwrite", overwrite),
        ("resume", resume),
    ])?;
    let recording = rgbd.is_some();
    let Some(input) = input.or(rgbd) else {
        return Err(PyValueError::new_err("input or rgbd must be given"));
    };
    let mut options = RunOptions::default();
    let p = &mut options.pipeline;
    p.rgbd = recording;
    p.depth_scale = depth_scale;
    p.depth_intrinsics = depth_intrinsics;
    p.depth_to_color = depth_to_color;
    p.keep_depth_edges = keep_depth_edges;
    p.depth_config = depth_config;
    p.intrinsics = intrinsics;
    p.fov_deg = fov_deg;
    p.depth = depth.unwrap_or(p.depth.clone());
    p.lambda = lambda_;
    p.mu = mu;
    p.smoothing = smoothing.unwrap_or(p.smoothing);
    p.latency = latency.unwrap_or(p.latency);
    p.mesh = match mesh {
        Some("image") => MeshKind::Image,
        Some("model") => MeshKind::Model,
        Some(_) => MeshKind::Face,
        None => p.mesh,
    };
    p.mode = match mode {
        Some("clip") => TemporalMode::Clip,
        Some(_) => TemporalMode::Streaming,
        None => p.mode,
    };
    p.subdivision = subdivision.unwrap_or(p.subdivision);
    p.fair = fair;
    p.keypoints = keypoints;
    p.spacing = spacing.unwrap_or(p.spacing);
    p.every = every.unwrap_or(p.every);
    p.max_frames = max_frames;
    p.models = models;
    if let Some(dir) = model {
        p.model = ModelSource::IctFolder(dir);
    } else if no_fit {
        p.model = ModelSource::None;
    }
    options.ply = ply;
    options.save_raw = save_raw;
    options.ascii = ascii;
    options.overwrite = overwrite;
    options.resume = resume;
    options.faces = match faces {
        Some("all") => Faces::All,
        Some(_) => Faces::Largest,
        None => options.faces,
    };
    options.exports.glb = glb;
    options.exports.texture = texture;
    options.exports.plots = plots;
    options.exports.report = report;
    options.exports.preview = preview;
    let stop = Arc::new(AtomicBool::new(false));
    let mut sink = PythonProgress {
        progress,
        notify,
        done: 0,
        total: None,
        stop: stop.clone(),
        raised: None,
    };
    let outcome = py.detach(|| visage::run_clip(&input, &out_dir, &options, &stop, &mut sink));
    if let Some(e) = sink.raised {
        return Err(e);
    }
    let runs = outcome.map_err(|e| error(visage::error_chain(&e)))?;
    let list = PyList::empty(py);
    for face in &runs {
        let d = PyDict::new(py);
        d.set_item("dir", &face.dir)?;
        d.set_item("frames", face.run.frames)?;
        d.set_item("meshed", face.run.meshed)?;
        d.set_item("kept", face.run.kept)?;
        let summary = face.run.summary.as_ref().map(serde_json::to_string);
        d.set_item("summary_json", summary.transpose().map_err(error)?)?;
        let exports = face.exports.as_ref().map(serde_json::to_string);
        d.set_item("exports_json", exports.transpose().map_err(error)?)?;
        list.append(d)?;
    }
    Ok(list)
}
