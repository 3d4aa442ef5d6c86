//! `visage run` as one call ([`run_clip`]), from its options ([`RunOptions`]): the output
//! folder claimed (one run per folder), the face or faces followed — each into its own folder
//! with `faces.json` listing them —, each face's run ([`run_into`]) and then its exports, and
//! the errors that say how a run that stopped left its folder and how to go on. The command
//! line and the Python package call it; they only print, or raise.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use visage_export::ExportSummary;
use visage_face::FaceTarget;
use visage_run_folder::{file_names, write_json_atomically, RunParameters};

use crate::{
    error_chain, first_faces, run_into, Error, Faces, FolderRun, FrameFilter, FrameSink,
    KeptFrames, RunOptions,
};

/// What [`run_clip`] tells its caller: each face's frames, warnings and notices, as a
/// [`FrameSink`], and each face's run once its files and exports are written.
pub trait ClipProgress: FrameSink {
    /// A face's run is done: its folder's files and its exports are written (`visage run`
    /// prints its closing lines here).
    fn face_done(&mut self, _face: &FaceRun) {}
}

/// One face's run into its folder, with its exports.
pub struct FaceRun {
    /// The folder: the output folder, or with [`Faces::All`] the face's `face-N/` in it.
    pub dir: PathBuf,
    /// What the run did (its `error` is `None`: a run that stopped is [`run_clip`]'s error).
    pub run: FolderRun,
    /// What the exports wrote; `None` when none were asked for, or when a resumed run was
    /// complete already (nothing was done).
    pub exports: Option<ExportSummary>,
}

/// Runs `input` (a video, image folder or image; with [`PipelineOptions::rgbd`] an RGB-D
/// recording) into the folder `out` as `visage run INPUT --out OUT` does with `options`: the
/// folder claimed ([`visage_run_folder::claim`]; what `overwrite` removed told to `sink` as a
/// [`FrameSink::caution`]), the face or faces followed, each face's files and then its exports
/// written. `sink` is told of each face's frames, warnings and notices, and of each face
/// done ([`ClipProgress::face_done`]); `stop` ends the input when it turns true (Ctrl-C). Returns
/// each face's run, in order.
///
/// # Errors
/// Before the run: an input that cannot be read, a folder that is taken or holds something
/// else, an option that cannot be used. A run that stopped: [`Error::RunInterrupted`],
/// [`Error::RunStopped`] (its source says why: [`Error::NoFace`] when no frame got a mesh),
/// which name what the folder holds and how to go on; [`Error::NoFaceInInput`] when no frame
/// shows a face for [`Faces::All`]; an export that failed. With [`Faces::All`], the first
/// face's error, after the other faces ran (an interruption ends the run at once).
///
/// [`PipelineOptions::rgbd`]: crate::PipelineOptions::rgbd
pub fn run_clip(
    input: &Path,
    out: &Path,
    options: &RunOptions,
    stop: &Arc<AtomicBool>,
    sink: &mut impl ClipProgress,
) -> Result<Vec<FaceRun>, Error> {
    let p = &options.pipeline;
    p.check_input(input)?;
    // With `resume`, a previous run is continued rather than refused.
    let claimed = visage_run_folder::claim(out, options.overwrite, options.resume)?;
    if let Some(cleared) = &claimed.cleared {
        sink.caution(&cleared.describe(out));
    }
    if options.faces == Faces::Largest {
        return Ok(vec![run_face(
            input,
            out,
            options,
            FaceTarget::Largest,
            stop,
            sink,
        )?]);
    }
    let models = p
        .models
        .clone()
        .unwrap_or_else(visage_face::model_files::models_dir);
    let faces = first_faces(p.open_input(input, sink)?, &models)?;
    if faces.is_empty() {
        return Err(Error::NoFaceInInput {
            path: input.to_owned(),
        });
    }
    sink.notice(&format!(
        "{} face{} in frame {}: each is tracked into its own folder",
        faces.len(),
        if faces.len() == 1 { "" } else { "s" },
        faces[0].0
    ));
    let mut runs = Vec::new();
    let mut records = Vec::new();
    let mut first_error = None;
    for (id, (frame, bbox)) in (1..).zip(&faces) {
        let folder = format!("{}{id}", file_names::FACE_FOLDER_PREFIX);
        let dir = out.join(&folder);
        let result = run_face(input, &dir, options, FaceTarget::Near(*bbox), stop, sink);
        let (status, meshed) = match &result {
            Ok(face) => ("complete".to_owned(), face.run.meshed),
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
        match result {
            Ok(face) => runs.push(face),
            Err(e) => {
                let interrupted = matches!(e, Error::RunInterrupted { .. });
                first_error.get_or_insert(e);
                if interrupted {
                    break;
                }
            }
        }
    }
    write_json_atomically(
        &out.join(file_names::FACES),
        &serde_json::json!({ "input": input.display().to_string(), "faces": records }),
    )?;
    first_error.map_or(Ok(runs), Err)
}

/// How the run in `dir` ended, as its metrics.json says (`"failed"` when it has none): its
/// status and the frames it meshed.
fn ended_as(dir: &Path) -> (String, usize) {
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

/// One tracked face's run into `dir` (continued with `resume`), then its exports.
fn run_face(
    input: &Path,
    dir: &Path,
    options: &RunOptions,
    target: FaceTarget,
    stop: &Arc<AtomicBool>,
    sink: &mut impl ClipProgress,
) -> Result<FaceRun, Error> {
    let (opened, reconstructor) = options.pipeline.open(input, target, sink)?;
    // The frames the texture is fused from, kept as they are decoded (no second decode).
    let kept = KeptFrames::default();
    let exporting = options.exports.any();
    let keep = exporting.then(|| {
        let select: FrameFilter = Box::new(visage_export::texture_frames(opened.frame_rate()));
        (select, kept.clone())
    });
    let folder = options.folder_options(input, target, keep, stop)?;
    // What the error advises: going on with `--resume`, or why this run cannot.
    let go_on = match reconstructor.parameters().cannot_resume() {
        None => "the same command with --resume goes on from there".to_owned(),
        Some(reason) => format!("it cannot be resumed: {reason}"),
    };
    let mut run = run_into(opened, reconstructor, dir, folder, sink)?;
    if run.summary.is_none() {
        let face = FaceRun {
            dir: dir.to_owned(),
            run,
            exports: None,
        };
        sink.face_done(&face);
        return Ok(face);
    }
    if let Some(e) = run.error.take() {
        return Err(stopped(input, dir, &run, e, go_on));
    }
    let exports = match exporting {
        true => Some(visage_export::export(
            dir,
            &options.exports,
            Some(&kept.take()),
        )?),
        false => None,
    };
    let face = FaceRun {
        dir: dir.to_owned(),
        run,
        exports,
    };
    sink.face_done(&face);
    Ok(face)
}

/// The error of a run into `dir` that stopped on `e`: what the folder holds and how to go on
/// (`go_on`).
fn stopped(input: &Path, dir: &Path, run: &FolderRun, e: Error, go_on: String) -> Error {
    let plural = |n: usize| if n == 1 { "" } else { "s" };
    let context = match e {
        Error::Interrupted => {
            return Error::RunInterrupted {
                frames: run.frames,
                dir: dir.to_owned(),
                go_on,
            }
        }
        Error::NoFace { .. } => format!(
            "{}: nothing to mesh ({} is in {})",
            input.display(),
            file_names::METRICS,
            dir.display()
        ),
        _ => {
            let kept = match run.finished {
                true => format!(
                    "stopped after {} frame{}: the files in {} hold {} frame{}",
                    run.frames,
                    plural(run.frames),
                    dir.display(),
                    run.kept,
                    plural(run.kept),
                ),
                false => format!(
                    "stopped after {} frame{}: what was written of them stays in {} under \
                     temporary names ({})",
                    run.frames,
                    plural(run.frames),
                    dir.display(),
                    file_names::TMP_SUFFIX
                ),
            };
            match &run.metrics_error {
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
            }
        }
    };
    Error::RunStopped {
        context,
        source: Box::new(e),
    }
}
