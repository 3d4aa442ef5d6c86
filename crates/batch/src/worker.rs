//! One worker's share of a batch: each clip of its shard run as `visage run` would, into a
//! temporary folder under `OUT/.partial/`, then renamed into place with its record, so that a
//! clip's folder appears whole or not at all.
//!
//! The temporary folder is `OUT/.partial/HASH.PID.N` (the id's FNV-1a hash, the worker's
//! process id, the clip's place in the shard), so that workers never share one and the next
//! worker of a shard can tell what a killed one left ([`Worker::clear_stale`]).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use visage_run_folder::{file_names, FolderLock};

use crate::clip_runner::{ClipError, ClipRunner};
use crate::error::Error;
use crate::manifest::Clip;
use crate::record::{self, Done, Failed, FileSum};
use crate::shard::fnv1a64;

/// Where clips are processed before they are renamed into place (under the batch folder).
pub const PARTIAL: &str = file_names::BATCH_PARTIAL_FOLDER;

/// The exit code recorded for a clip whose run panicked: `visage`'s for an internal error.
const PANICKED_EXIT_CODE: u8 = 1;

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
#[derive(Clone, Debug)]
pub struct Worker {
    /// The batch folder: `OUT/ID/` per clip.
    pub out: PathBuf,
    /// Options for every clip, after the clip's own.
    pub common: Vec<String>,
    /// Run clips again that failed before (their `error.json`); else they are kept.
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

    /// Removes what earlier, killed workers left in `.partial/` for `clips` (this shard's). A
    /// folder whose run folder lock is held (`visage_run_folder::FolderLock`: a live worker,
    /// started twice on the same shard, is writing there) is left alone.
    pub fn clear_stale(&self, clips: &[Clip]) -> Result<usize, Error> {
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
            let path = entry.map_err(Error::Io)?.path();
            let name = path.file_name().unwrap_or_default().to_string_lossy();
            if ours.contains(name.split('.').next().unwrap_or_default()) {
                let live = path.join(file_names::LOCK).exists()
                    && matches!(
                        FolderLock::acquire(&path),
                        Err(visage_run_folder::RunFolderError::Locked { .. })
                    );
                if live {
                    continue;
                }
                remove_dir_all(&path)?;
                removed += 1;
            }
        }
        Ok(removed)
    }

    /// Runs `clips` (this shard's) with `runner`, `jobs` at a time, until `stop` turns true;
    /// `log` gets a line per clip. The outcomes of the clips started, by index into `clips`,
    /// in order.
    pub fn run_all(
        &self,
        clips: &[Clip],
        jobs: usize,
        runner: &impl ClipRunner,
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
                    let ran = std::thread::scope(|s| {
                        s.spawn(|| self.run_clip(clip, i, runner, stop)).join()
                    });
                    let outcome = match ran {
                        Ok(Ok((outcome, message))) => {
                            log(&format!(
                                "[{}/{}] {}: {message}",
                                i + 1,
                                clips.len(),
                                clip.id
                            ));
                            outcome
                        }
                        // The batch's own files could not be written, or the worker's code
                        // panicked: the clip is not placed and counts as failed.
                        ran => {
                            let why = match ran {
                                Ok(Err(e)) => visage::error_chain(&e),
                                _ => "internal error: the clip's thread panicked".to_owned(),
                            };
                            log(&format!(
                                "[{}/{}] {}: failed: {why}",
                                i + 1,
                                clips.len(),
                                clip.id,
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
        runner: &impl ClipRunner,
        stop: &Arc<AtomicBool>,
    ) -> Result<(Outcome, String), Error> {
        let folder = self.out.join(&clip.id);
        let options = clip.options_with(&self.common);
        let why = record::not_done(&folder, &clip.input, &options);
        if why.is_none() {
            return Ok((Outcome::Skipped, "done before; skipped".into()));
        }
        if !self.retry_failed && folder.join(record::ERROR).is_file() {
            return Ok((
                Outcome::Failed { now: false },
                format!(
                    "failed before ({}); kept, --retry-failed runs it again",
                    record::ERROR
                ),
            ));
        }
        let tmp = self.partial_dir(clip, attempt);
        if tmp.exists() {
            remove_dir_all(&tmp)?;
        }
        create_dir_all(&tmp)?;
        let started = Instant::now();
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            runner.run(clip, &tmp, &options, stop)
        }))
        .unwrap_or_else(|panic| {
            let what = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "a panic".into());
            Err(ClipError::Failed {
                exit_code: PANICKED_EXIT_CODE,
                error: format!("internal error: {what}"),
            })
        });
        let seconds = started.elapsed().as_secs_f64();
        // A stop signal also reaches the decoder (FFmpeg, in the same process group), whose
        // end then reads as a broken video: any error after the signal is the signal's.
        let result = match result {
            Err(_) if stop.load(Ordering::SeqCst) => Err(ClipError::Interrupted),
            result => result,
        };
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
                write_record(&tmp.join(record::DONE), &done)?;
                (
                    Outcome::Done { frames, meshed },
                    format!("done, {frames} frames ({meshed} meshed) in {seconds:.1} s"),
                )
            }
            Err(ClipError::Interrupted) => {
                std::fs::remove_dir_all(&tmp).ok();
                return Ok((Outcome::Interrupted, "interrupted; not placed".into()));
            }
            Err(ClipError::Failed { exit_code, error }) => {
                let failed = Failed {
                    clip: clip.id.clone(),
                    input: clip.input.clone(),
                    exit_code,
                    error: error.clone(),
                    options,
                    visage_version: env!("CARGO_PKG_VERSION").into(),
                };
                write_record(&tmp.join(record::ERROR), &failed)?;
                (Outcome::Failed { now: true }, format!("failed: {error}"))
            }
        };
        self.place(&tmp, &folder, clip)?;
        Ok((outcome, message))
    }

    /// Renames `tmp` to `folder`, replacing a folder there that is not done (a failed or
    /// stale clip); a done folder that appeared meanwhile (another worker) wins.
    fn place(&self, tmp: &Path, folder: &Path, clip: &Clip) -> Result<(), Error> {
        if let Some(parent) = folder.parent() {
            create_dir_all(parent)?;
        }
        if folder.exists() {
            if record::not_done(folder, &clip.input, &clip.options_with(&self.common)).is_none() {
                std::fs::remove_dir_all(tmp).ok();
                return Ok(());
            }
            let old = tmp.with_extension("old");
            std::fs::rename(folder, &old).map_err(|source| Error::MoveAside {
                path: folder.to_owned(),
                source,
            })?;
            remove_dir_all(&old)?;
        }
        std::fs::rename(tmp, folder).map_err(|source| Error::Rename {
            from: tmp.to_owned(),
            to: folder.to_owned(),
            source,
        })
    }
}

/// Frames processed and meshed, from `metrics.json` in `dir` (and its `face-N/` folders).
fn frames_in(dir: &Path) -> (u64, u64) {
    let read = |d: &Path| -> (u64, u64) {
        let m: serde_json::Value = std::fs::read(d.join(file_names::METRICS))
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
                .starts_with(file_names::FACE_FOLDER_PREFIX)
            {
                let (f, m) = read(&e.path());
                frames = frames.max(f);
                meshed += m;
            }
        }
    }
    (frames, meshed)
}

/// Writes a clip's record through a temporary file (`visage`'s one way to do that).
fn write_record(path: &Path, record: &impl serde::Serialize) -> Result<(), Error> {
    visage_run_folder::write_json_atomically(path, record).map_err(|e| Error::Record(Box::new(e)))
}

fn create_dir_all(path: &Path) -> Result<(), Error> {
    std::fs::create_dir_all(path).map_err(|source| Error::Create {
        path: path.to_owned(),
        source,
    })
}

fn remove_dir_all(path: &Path) -> Result<(), Error> {
    std::fs::remove_dir_all(path).map_err(|source| Error::Remove {
        path: path.to_owned(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::BoxError;

    /// Writes `metrics.json` (3 frames, 2 solved) and `mesh.obj`, fails on clips named
    /// `bad*` (exit code 3), panics on `panic*`, stops on `stop*`.
    struct Fake;

    impl ClipRunner for Fake {
        fn check(&self, _: &Clip, _: &[String]) -> Result<(), BoxError> {
            Ok(())
        }

        fn run(
            &self,
            clip: &Clip,
            out: &Path,
            _: &[String],
            stop: &Arc<AtomicBool>,
        ) -> Result<(), ClipError> {
            if clip.id.starts_with("panic") {
                panic!("the fake panicked");
            }
            if clip.id.starts_with("stop") {
                stop.store(true, Ordering::SeqCst);
                return Err(ClipError::Interrupted);
            }
            let metrics = r#"{"summary": {"frames": 3, "solved": 2, "carried": 0}}"#;
            std::fs::write(out.join("metrics.json"), metrics).unwrap();
            if clip.id.starts_with("bad") {
                return Err(ClipError::Failed {
                    exit_code: 3,
                    error: "no face in any frame".into(),
                });
            }
            std::fs::write(out.join("mesh.obj"), "v 0 0 1\n").unwrap();
            Ok(())
        }
    }

    fn clips(dir: &Path, ids: &[&str]) -> Vec<Clip> {
        ids.iter()
            .enumerate()
            .map(|(i, id)| {
                let input = dir.join(format!("{}.mp4", id.replace('/', "-")));
                std::fs::write(&input, id).unwrap();
                Clip {
                    line: i + 1,
                    id: id.to_string(),
                    input,
                    options: vec!["--every".into(), "2".into()],
                }
            })
            .collect()
    }

    #[test]
    fn clips_are_placed_whole_with_their_records_and_skipped_when_done() {
        let tmp = tempfile::tempdir().unwrap();
        let clips = clips(tmp.path(), &["day1/a", "bad", "panic"]);
        let worker = Worker {
            out: tmp.path().join("out"),
            common: vec!["--glb".into()],
            retry_failed: false,
        };
        let stop = Arc::new(AtomicBool::new(false));
        let lines = Mutex::new(Vec::new());
        let log = |l: &str| lines.lock().unwrap().push(l.to_owned());
        let results = worker.run_all(&clips, 2, &Fake, &stop, log);
        let outcomes: Vec<_> = results.iter().map(|(_, o)| o.clone()).collect();
        assert_eq!(
            outcomes,
            [
                Outcome::Done {
                    frames: 3,
                    meshed: 2
                },
                Outcome::Failed { now: true },
                Outcome::Failed { now: true }
            ]
        );
        let a = worker.out.join("day1/a");
        let done: Done =
            serde_json::from_slice(&std::fs::read(a.join(record::DONE)).unwrap()).unwrap();
        assert_eq!(done.options, ["--every", "2", "--glb"]);
        assert_eq!(
            done.outputs.keys().collect::<Vec<_>>(),
            ["mesh.obj", "metrics.json"]
        );
        let failed = |id: &str| -> Failed {
            let path = worker.out.join(id).join(record::ERROR);
            serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
        };
        assert_eq!(failed("bad").exit_code, 3);
        assert_eq!(failed("panic").exit_code, PANICKED_EXIT_CODE);
        assert_eq!(failed("panic").error, "internal error: the fake panicked");
        assert_eq!(
            std::fs::read_dir(worker.out.join(PARTIAL)).unwrap().count(),
            0,
            "nothing is left half done"
        );
        let lines = lines.into_inner().unwrap();
        assert!(
            lines.contains(&"[2/3] bad: failed: no face in any frame".to_owned()),
            "{lines:?}"
        );

        let again = worker.run_all(&clips, 1, &Fake, &stop, |_| {});
        assert_eq!(again[0].1, Outcome::Skipped);
        assert_eq!(again[1].1, Outcome::Failed { now: false });
    }

    #[test]
    fn a_stopped_clip_is_not_placed_and_the_rest_do_not_start() {
        let tmp = tempfile::tempdir().unwrap();
        let clips = clips(tmp.path(), &["stop", "b"]);
        let worker = Worker {
            out: tmp.path().join("out"),
            common: Vec::new(),
            retry_failed: false,
        };
        let stop = Arc::new(AtomicBool::new(false));
        let results = worker.run_all(&clips, 1, &Fake, &stop, |_| {});
        assert_eq!(results, [(0, Outcome::Interrupted)]);
        assert!(!worker.out.join("stop").exists());
        assert_eq!(
            std::fs::read_dir(worker.out.join(PARTIAL)).unwrap().count(),
            0
        );
    }

    #[test]
    fn stale_folders_of_this_shards_clips_are_removed() {
        let tmp = tempfile::tempdir().unwrap();
        let clips = clips(tmp.path(), &["a", "b"]);
        let worker = Worker {
            out: tmp.path().join("out"),
            common: Vec::new(),
            retry_failed: false,
        };
        let partial = worker.out.join(PARTIAL);
        let ours = format!("{:016x}.1.0", fnv1a64(b"a"));
        let theirs = format!("{:016x}.1.0", fnv1a64(b"other"));
        std::fs::create_dir_all(partial.join(&ours)).unwrap();
        std::fs::create_dir_all(partial.join(&theirs)).unwrap();
        assert_eq!(worker.clear_stale(&clips).unwrap(), 1);
        assert!(partial.join(&theirs).exists() && !partial.join(&ours).exists());

        // A clip folder that a live worker's run holds is left alone until it lets go.
        std::fs::create_dir_all(partial.join(&ours)).unwrap();
        let live = FolderLock::acquire(&partial.join(&ours)).unwrap();
        assert_eq!(worker.clear_stale(&clips).unwrap(), 0);
        assert!(partial.join(&ours).exists());
        drop(live);
        assert_eq!(worker.clear_stale(&clips).unwrap(), 1);
        assert!(!partial.join(&ours).exists());
    }
}
