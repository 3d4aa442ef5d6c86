//! A whole input run into an output folder, as `visage run`, the batch worker and other
//! front ends do it ([`run_into`]): the folder's streams (the point cache, PLYs on request,
//! `landmarks.json`, the blendshape curves, `camera.json`, and `metrics.json` from the start,
//! saying `"running"`), continuing a run that stopped part-way, the rule that a run which
//! meshed no frame found no face, the fitted identity, and the final `metrics.json` whatever
//! happened.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::input::FrameFilter;
use crate::{Error, FaceTarget, FrameSink, Input, KeptFrames, MeshFrame, Reconstructor};
use visage_mesh::io::PlyFormat;
use visage_rig::BlendshapeFrame;
use visage_run_folder::{
    file_names, prepare_resume, FrameMetrics, LandmarksFrame, OutputDir, ResumePoint, ResumeState,
    RunDescription, RunSummary,
};

/// What [`run_into`] writes besides the point cache, `landmarks.json`, `camera.json` and
/// `metrics.json`, and how it treats a previous run.
pub struct FolderOptions {
    /// The input as the user named it (`metrics.json`'s `input`; a resumed run must name the
    /// same).
    pub input_name: String,
    /// The input file by content, when it is one file (`metrics.json`'s `input_file`: a
    /// resumed run must read the same bytes; `visage export` finds it by its absolute path).
    pub input_file: Option<visage_run_folder::InputFile>,
    /// Continue the run in the folder when it stopped part-way; without it the folder is
    /// written afresh (see [`visage_run_folder::claim`] for refusing one that is not empty).
    pub resume: bool,
    /// A PLY per meshed frame: the format, whether the fused surface (`meshes/`) and the raw
    /// one (`raw/`) are written.
    pub ply: (PlyFormat, bool, bool),
    /// Whether the blendshape curves are written (when the model is fitted).
    pub blendshapes: bool,
    /// Which frames to keep copies of, as they are decoded, for after the run (e.g. those a
    /// texture is fused from), and where.
    pub keep: Option<(FrameFilter, KeptFrames)>,
    /// Ends the input when it turns true (Ctrl-C): the frames read so far go through every
    /// stage and are written, and the run's error is [`Error::Interrupted`].
    pub stop: Option<Arc<AtomicBool>>,
    /// The face the run follows (only said in the warning about other faces in view).
    pub target: FaceTarget,
}

/// What a run into a folder did.
pub struct FolderRun {
    /// Frames of the folder's run that have a mesh, the earlier runs' of a resumed one
    /// included.
    pub meshed: usize,
    /// Frames this run processed (its warm-up included).
    pub frames: usize,
    /// This run's summary; `None` when the folder held a complete run already and `resume`
    /// was asked for (nothing was done).
    pub summary: Option<RunSummary>,
    /// Where a resumed run continued.
    pub resumed: Option<ResumePoint>,
    /// Why the run stopped early — [`Error::Interrupted`], [`Error::NoFace`] or another
    /// error —; the frames before it are written, and `metrics.json` says so. The first thing
    /// that went wrong: a later failure to write `metrics.json` is [`FolderRun::metrics_error`].
    pub error: Option<Error>,
    /// Frames the folder's files hold (a resumed run's kept frames included).
    pub kept: usize,
    /// Whether the streamed files are under their final names; `false` after a write failed
    /// (they stay `.tmp`, where `--resume` finds them).
    pub finished: bool,
    /// Why `metrics.json` could not be written after the run's error (it then still says
    /// `"running"`, as after a kill, and `--resume` goes on all the same).
    pub metrics_error: Option<Error>,
}

/// Runs `input` through `reconstructor` into the folder `dir` (created if missing), streaming
/// each frame's outputs as it is done; `progress` is told of every frame done, of warnings
/// and of notices (what a resume keeps). A run stopped part-way — killed, interrupted, failed —
/// leaves its frames so far and a `metrics.json` that says so, and `resume` continues it.
///
/// # Errors
/// Before the run starts: a previous run that cannot be continued, a folder that cannot be
/// written. Errors during the run are [`FolderRun::error`].
pub fn run_into(
    mut input: Input,
    reconstructor: Reconstructor,
    dir: &Path,
    options: FolderOptions,
    progress: &mut impl FrameSink,
) -> Result<FolderRun, Error> {
    let selection = input.selection();
    let description = RunDescription {
        input: &options.input_name,
        input_file: options.input_file.as_ref(),
        intrinsics: reconstructor.intrinsics(),
        parameters: reconstructor.parameters(),
        selection,
    };
    let resume = match options.resume {
        true => prepare_resume(dir, &description)?,
        false => ResumeState::Fresh,
    };
    let point = match resume {
        ResumeState::Fresh => None,
        ResumeState::Complete { frames } => {
            progress.notice(&format!(
                "{}: the run there is complete ({frames} frames); nothing to resume",
                dir.display()
            ));
            return Ok(FolderRun {
                meshed: meshed_in(dir),
                frames: 0,
                summary: None,
                resumed: None,
                error: None,
                kept: frames,
                finished: true,
                metrics_error: None,
            });
        }
        ResumeState::Continue(point) => {
            progress.notice(&format!(
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
            ));
            if let Some(index) = point.warm_up_after {
                input = input.after(index);
            }
            Some(point)
        }
    };
    if let Some((select, kept)) = options.keep {
        input = input.keep_copies(select, kept);
    }
    let mut out = OutputDir::create(dir)?;
    if let Some(point) = &point {
        out = out.resuming(point.clone());
    }
    let (format, fused, raw) = options.ply;
    out = out
        .with_ply(format, fused, raw)?
        .with_point_cache()?
        .with_landmarks()?;
    if options.blendshapes {
        out = out.with_blendshapes(input.frame_rate())?;
    }
    // The camera the meshes are in: `visage render MESH --intrinsics OUT/camera.json`.
    out.write_camera(reconstructor.intrinsics())?;
    out.write_running(&description)?;
    let stop = options.stop;
    if let Some(stop) = &stop {
        input = input.stop_on(stop.clone());
    }
    progress.started(input.frames_to_process());
    let mut sink = Tee {
        out,
        progress: &mut *progress,
    };
    let mut outcome = reconstructor.run(input, &mut sink);
    let mut out = sink.out;
    progress.ended();
    if stop.is_some_and(|s| s.load(Ordering::SeqCst)) && outcome.error.is_none() {
        outcome.error = Some(Error::Interrupted);
    }
    let s = &outcome.summary;
    if let (FaceTarget::Largest, true, Some(frame)) =
        (options.target, s.most_faces_seen > 1, s.most_faces_frame)
    {
        progress.warning(&format!(
            "{} faces were in view (first in frame {frame}); only the largest was meshed \
             (--faces all meshes each)",
            s.most_faces_seen
        ));
    }
    if outcome.error.is_none() && s.frames > 0 && s.solved + s.carried == 0 {
        let unfit = outcome.frames.iter().filter(|f| f.fit_error.is_some());
        outcome.error = Some(Error::NoFace {
            frames: s.frames,
            unfit: unfit.clone().count(),
            reason: unfit.clone().find_map(|f| f.fit_error.clone()),
        });
    }
    let finished = match out.finish() {
        Ok(()) => outcome.error.is_none() || !out.write_failed(),
        Err(e) => {
            outcome.error.get_or_insert(e.into());
            false
        }
    };
    if let Some(identity) = &outcome.identity {
        // A failure here still leaves a metrics.json that says so.
        let written = out.write_identity(
            &identity.neutral_mesh(),
            &identity.coefficients,
            identity.frames,
        );
        if let (Err(e), None) = (written, &outcome.error) {
            outcome.error = Some(e.into());
        }
    }
    let mut report = outcome.report(&options.input_name);
    report.selection = Some(selection);
    // The warm-up frames' records are the previous run's, unless it was killed before it
    // wrote them: then the warm-up's own stand for them.
    let mut earlier_meshed = 0;
    let mut warm_up_records = std::collections::HashMap::new();
    if let Some(point) = &point {
        let warm_up = |f: &FrameMetrics| f.index <= point.after_frame;
        let warm_meshed = report.frames.iter().filter(|f| warm_up(f) && f.has_mesh());
        earlier_meshed = point.meshed.saturating_sub(warm_meshed.count());
        for f in report.frames.iter().filter(|f| warm_up(f)) {
            if let Ok(v) = serde_json::to_value(f) {
                warm_up_records.insert(f.index, v);
            }
        }
        report.frames.retain(|f| !warm_up(f));
    }
    report.resumed = point.clone();
    // Every frame the files hold: the kept frames' records, then this run's new ones.
    let mut metrics = serde_json::to_value(&report).map_err(|e| {
        Error::from(visage_run_folder::RunFolderError::Input {
            path: dir.join(visage_run_folder::file_names::METRICS),
            reason: format!("cannot encode the run's figures: {e}"),
        })
    })?;
    if let (Some(file), Some(fields)) = (&options.input_file, metrics.as_object_mut()) {
        // After `input`, where a reader looks for it.
        let at = fields
            .keys()
            .position(|k| k == "input")
            .map_or(fields.len(), |i| i + 1);
        if let Ok(v) = serde_json::to_value(file) {
            fields.shift_insert(at, "input_file".to_owned(), v);
        }
    }
    if let (Some(point), Some(frames)) = (&point, metrics["frames"].as_array_mut()) {
        let kept = point.kept_records.iter().map(|r| {
            let warm = r["restored"]
                .as_bool()
                .unwrap_or(false)
                .then(|| r["index"].as_u64())
                .flatten()
                .and_then(|i| warm_up_records.remove(&(i as usize)));
            warm.unwrap_or_else(|| r.clone())
        });
        frames.splice(0..0, kept.collect::<Vec<_>>());
    }
    let mut metrics_error = None;
    if let Err(e) = out.write_metrics(&metrics) {
        match outcome.error {
            None => outcome.error = Some(e.into()),
            Some(_) => metrics_error = Some(e.into()),
        }
    }
    Ok(FolderRun {
        kept: out.frames_written(),
        finished,
        metrics_error,
        meshed: earlier_meshed + outcome.summary.solved + outcome.summary.carried,
        frames: outcome.frames.len(),
        summary: Some(outcome.summary),
        resumed: point,
        error: outcome.error,
    })
}

/// The output folder, with the frames' progress and warnings told to the caller's sink.
struct Tee<'a, S> {
    out: OutputDir,
    progress: &'a mut S,
}

impl<S: FrameSink> FrameSink for Tee<'_, S> {
    fn landmarks(&mut self, record: &LandmarksFrame) -> Result<(), Error> {
        self.out.landmarks(record)
    }
    fn mesh(&mut self, frame: &MeshFrame<'_>) -> Result<(), Error> {
        self.out.mesh(frame)
    }
    fn blendshapes(&mut self, frame: &BlendshapeFrame) -> Result<(), Error> {
        self.out.blendshapes(frame)
    }
    fn frame_done(&mut self, metrics: &FrameMetrics) {
        self.progress.frame_done(metrics);
    }
    fn warning(&mut self, message: &str) {
        self.progress.warning(message);
    }
}

/// The frames a complete run in `dir` meshed, as its `metrics.json` says (0 when it does not).
fn meshed_in(dir: &Path) -> usize {
    let metrics = std::fs::read(dir.join(file_names::METRICS))
        .ok()
        .and_then(|bytes| serde_json::from_slice::<serde_json::Value>(&bytes).ok())
        .unwrap_or_default();
    let count = |key: &str| metrics["summary"][key].as_u64().unwrap_or(0) as usize;
    let earlier = metrics["resumed"]["meshed"].as_u64().unwrap_or(0) as usize;
    earlier + count("solved") + count("carried")
}
