//! One worker's share of a batch: each clip of its shard run as `visage run` would, into a
//! temporary folder under `OUT/.partial/`, then renamed into place with its record, so that a
//! clip's folder appears whole or not at all.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use anyhow::Context;
use clap::Parser;

use super::manifest::Clip;
use super::record::{self, Done, Failed, FileSum};
use super::shard::fnv1a64;
use crate::commands::run::{run_with_stop, RunArgs};
use crate::exit::Failure;
use crate::interrupt;

/// Where clips are processed before they are renamed into place.
pub const PARTIAL: &str = ".partial";

/// `visage run`'s flags, parsed as the command line would be.
#[derive(Parser)]
#[command(name = "visage run", no_binary_name = false)]
struct RunLine {
    #[command(flatten)]
    run: RunArgs,
}

/// Flags the batch sets itself.
const RESERVED: [&str; 3] = ["--out", "--overwrite", "--resume"];

/// The `visage run` arguments of `clip` into `out` with `options`.
fn run_args(clip: &Clip, out: &Path, options: &[String]) -> anyhow::Result<RunArgs> {
    if let Some(flag) = options
        .iter()
        .find(|o| RESERVED.iter().any(|r| o.split('=').next() == Some(*r)))
    {
        anyhow::bail!("{flag} is set by `visage batch` itself (each clip goes to OUT/ID)");
    }
    let mut line = vec![
        "visage run".to_owned(),
        clip.input.display().to_string(),
        "--out".to_owned(),
        out.display().to_string(),
        "--quiet".to_owned(),
    ];
    line.extend(options.iter().cloned());
    RunLine::try_parse_from(line)
        .map(|l| l.run)
        .map_err(|e| anyhow::anyhow!("{}", e.render().to_string().trim_end()))
}

/// Checks every clip's options before any work starts (a typo fails the invocation).
pub fn check_options(clips: &[Clip], common: &[String]) -> anyhow::Result<()> {
    for clip in clips {
        let options = options_of(clip, common);
        run_args(clip, Path::new("out"), &options)
            .with_context(|| format!("manifest line {} ({}): bad options", clip.line, clip.id))?;
    }
    Ok(())
}

/// The clip's own options, then the batch's.
pub fn options_of(clip: &Clip, common: &[String]) -> Vec<String> {
    clip.options.iter().chain(common).cloned().collect()
}

/// What happened to one clip.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// Processed now: frames and meshed frames.
    Done { frames: u64, meshed: u64 },
    /// A valid `done.json` was there.
    Skipped,
    /// Failed now or before (kept without `--retry-failed`).
    Failed { now: bool },
    /// Stopped by Ctrl-C or SIGTERM: nothing was placed.
    Interrupted,
}

/// A worker over its shard's clips.
pub struct Worker {
    pub out: PathBuf,
    pub common: Vec<String>,
    pub retry_failed: bool,
}

impl Worker {
    /// The temporary folder of `clip` for this process (unique per process and attempt).
    fn partial_dir(&self, clip: &Clip, attempt: usize) -> PathBuf {
        self.out.join(PARTIAL).join(format!(
            "{:016x}.{}.{attempt}",
            fnv1a64(clip.id.as_bytes()),
            std::process::id()
        ))
    }

    /// Removes what earlier, killed workers left in `.partial/` for `clips` (this shard's):
    /// one live worker per shard is assumed.
    pub fn clear_stale(&self, clips: &[Clip]) -> anyhow::Result<usize> {
        let dir = self.out.join(PARTIAL);
        let Ok(entries) = std::fs::read_dir(&dir) else {
            return Ok(0);
        };
        let ours: std::collections::HashSet<String> = clips
            .iter()
            .map(|c| format!("{:016x}", fnv1a64(c.id.as_bytes())))
            .collect();
        let mut removed = 0;
        for entry in entries {
            let path = entry?.path();
            let name = path.file_name().unwrap_or_default().to_string_lossy();
            if ours.contains(name.split('.').next().unwrap_or_default()) {
                std::fs::remove_dir_all(&path)
                    .with_context(|| format!("{}: cannot remove", path.display()))?;
                removed += 1;
            }
        }
        Ok(removed)
    }

    /// Runs `clips` (this shard's), `jobs` at a time; `log` gets a line per clip.
    pub fn run_all(
        &self,
        clips: &[Clip],
        jobs: usize,
        stop: &Arc<AtomicBool>,
        log: impl Fn(&str) + Sync,
    ) -> Vec<(usize, Outcome)> {
        let next = AtomicUsize::new(0);
        let results = Mutex::new(Vec::new());
        std::thread::scope(|s| {
            for _ in 0..jobs.max(1) {
                s.spawn(|| loop {
                    if stop.load(Ordering::SeqCst) {
                        break;
                    }
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    let Some(clip) = clips.get(i) else { break };
                    // Each clip on a thread of its own: run one after another from one
                    // thread, the model fit's matrix products (faer's f32 GEMM) took about 18×
                    // longer from the third clip on (perf samples; the cause is not
                    // understood), which made the worker 8–14 % slower than a loop of
                    // `visage run`.
                    let ran =
                        std::thread::scope(|s| s.spawn(|| self.run_clip(clip, i, stop)).join());
                    let ran = ran.unwrap_or_else(|_| {
                        Err(anyhow::anyhow!(
                            "internal error: the clip's thread panicked"
                        ))
                    });
                    let outcome = match ran {
                        Ok((outcome, message)) => {
                            log(&format!(
                                "[{}/{}] {}: {message}",
                                i + 1,
                                clips.len(),
                                clip.id
                            ));
                            outcome
                        }
                        Err(e) => {
                            // The batch's own files could not be written: the clip is
                            // not placed and counts as failed.
                            log(&format!(
                                "[{}/{}] {}: failed: {}",
                                i + 1,
                                clips.len(),
                                clip.id,
                                visage::error_chain(e.as_ref())
                            ));
                            Outcome::Failed { now: true }
                        }
                    };
                    results
                        .lock()
                        .expect("no panic holds it")
                        .push((i, outcome));
                });
            }
        });
        let mut results = results.into_inner().expect("threads joined");
        results.sort_by_key(|(i, _)| *i);
        results
    }

    /// One clip: skipped when done, else processed and placed; the outcome and a line for
    /// the log.
    fn run_clip(
        &self,
        clip: &Clip,
        attempt: usize,
        stop: &Arc<AtomicBool>,
    ) -> anyhow::Result<(Outcome, String)> {
        let folder = self.out.join(&clip.id);
        let options = options_of(clip, &self.common);
        let why = record::not_done(&folder, &clip.input, &options);
        if why.is_none() {
            return Ok((Outcome::Skipped, "done before; skipped".into()));
        }
        if !self.retry_failed && folder.join(record::ERROR).is_file() {
            return Ok((
                Outcome::Failed { now: false },
                "failed before (error.json); kept, --retry-failed runs it again".into(),
            ));
        }
        let tmp = self.partial_dir(clip, attempt);
        if tmp.exists() {
            std::fs::remove_dir_all(&tmp)
                .with_context(|| format!("{}: cannot remove", tmp.display()))?;
        }
        std::fs::create_dir_all(&tmp)
            .with_context(|| format!("{}: cannot create", tmp.display()))?;
        let started = Instant::now();
        let args = run_args(clip, &tmp, &options)?;
        let result =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run_with_stop(args, stop)))
                .unwrap_or_else(|panic| {
                    let what = panic
                        .downcast_ref::<String>()
                        .cloned()
                        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                        .unwrap_or_else(|| "a panic".into());
                    Err(Failure {
                        code: crate::exit::INTERNAL,
                        error: anyhow::anyhow!("internal error: {what}"),
                    }
                    .into())
                });
        let seconds = started.elapsed().as_secs_f64();
        let (outcome, message) = match result {
            Ok(()) => {
                let (frames, meshed) = frames_in(&tmp);
                let done = Done {
                    clip: clip.id.clone(),
                    input: clip.input.clone(),
                    input_file: FileSum::of(&clip.input)?,
                    input_modified_s: record::modified_s(&clip.input),
                    options,
                    visage_version: env!("CARGO_PKG_VERSION").into(),
                    frames,
                    meshed,
                    seconds,
                    outputs: record::output_sums(&tmp)?,
                };
                visage::write_json_atomically(&tmp.join(record::DONE), &done)?;
                (
                    Outcome::Done { frames, meshed },
                    format!("done, {frames} frames ({meshed} meshed) in {seconds:.1} s"),
                )
            }
            // A stop signal also reaches the decoder (FFmpeg, in the same process group), whose
            // end then reads as a broken video: any error after the signal is the signal's.
            Err(e) if is_interrupted(&e) || stop.load(Ordering::SeqCst) => {
                std::fs::remove_dir_all(&tmp).ok();
                return Ok((Outcome::Interrupted, "interrupted; not placed".into()));
            }
            Err(e) => {
                let code = crate::exit::code_of(&e);
                let error = visage::error_chain(e.as_ref());
                let failed = Failed {
                    clip: clip.id.clone(),
                    input: clip.input.clone(),
                    exit_code: code,
                    error: error.clone(),
                    options,
                    visage_version: env!("CARGO_PKG_VERSION").into(),
                };
                visage::write_json_atomically(&tmp.join(record::ERROR), &failed)?;
                (Outcome::Failed { now: true }, format!("failed: {error}"))
            }
        };
        self.place(&tmp, &folder, clip)?;
        Ok((outcome, message))
    }

    /// Renames `tmp` to `folder`, replacing a folder there that is not done (a failed or
    /// stale clip); a done folder that appeared meanwhile (another worker) wins.
    fn place(&self, tmp: &Path, folder: &Path, clip: &Clip) -> anyhow::Result<()> {
        if let Some(parent) = folder.parent() {
            std::fs::create_dir_all(parent)
                .with_context(|| format!("{}: cannot create", parent.display()))?;
        }
        if folder.exists() {
            if record::not_done(folder, &clip.input, &options_of(clip, &self.common)).is_none() {
                std::fs::remove_dir_all(tmp).ok();
                return Ok(());
            }
            let old = tmp.with_extension("old");
            std::fs::rename(folder, &old)
                .with_context(|| format!("{}: cannot move aside", folder.display()))?;
            std::fs::remove_dir_all(&old)
                .with_context(|| format!("{}: cannot remove", old.display()))?;
        }
        std::fs::rename(tmp, folder)
            .with_context(|| format!("cannot rename {} to {}", tmp.display(), folder.display()))
    }
}

/// Frames processed and meshed, from `metrics.json` in `dir` (and its `face-N/` folders).
fn frames_in(dir: &Path) -> (u64, u64) {
    let read = |d: &Path| -> (u64, u64) {
        let m: serde_json::Value = std::fs::read(d.join("metrics.json"))
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok())
            .unwrap_or_default();
        let n = |k: &str| m["summary"][k].as_u64().unwrap_or(0);
        (n("frames"), n("solved") + n("carried"))
    };
    let (mut frames, mut meshed) = read(dir);
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            if e.file_name()
                .to_string_lossy()
                .starts_with(visage::file_names::FACE_FOLDER_PREFIX)
            {
                let (f, m) = read(&e.path());
                frames = frames.max(f);
                meshed += m;
            }
        }
    }
    (frames, meshed)
}

fn is_interrupted(e: &anyhow::Error) -> bool {
    e.downcast_ref::<Failure>()
        .is_some_and(|f| f.code == interrupt::INTERRUPTED)
}
