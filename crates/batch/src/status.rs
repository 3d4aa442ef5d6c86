//! The status of a batch folder (`visage batch status`): done, failed and missing clips per
//! shard, the failures' first lines, the missing ids, and the folders in progress.

use std::path::Path;

use serde::Serialize;

use crate::batch_record::BatchRecord;
use crate::error::Error;
use crate::manifest::{self, Clip};
use crate::record;
use crate::shard::shard_of;
use crate::worker::PARTIAL;

/// One clip's state in the batch folder.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum State {
    /// A valid `done.json`.
    Done,
    /// An `error.json`.
    Failed,
    /// Neither (not yet run, running, or killed).
    Missing,
}

/// The state of `clip` under `out`, with the batch's `common` options.
pub fn state(out: &Path, clip: &Clip, common: &[String]) -> State {
    let folder = out.join(&clip.id);
    let options = clip.options_with(common);
    if record::not_done(&folder, &clip.input, &options).is_none() {
        State::Done
    } else if folder.join(record::ERROR).is_file() {
        State::Failed
    } else {
        State::Missing
    }
}

/// Counts of one shard.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ShardStatus {
    /// The shard's index.
    pub shard: usize,
    /// Its clips, and of them the done, failed and missing ones.
    pub clips: usize,
    pub done: usize,
    pub failed: usize,
    pub missing: usize,
    /// Failed clips: id and the first line of the reason.
    pub failures: Vec<(String, String)>,
    /// Missing clips' ids.
    pub missing_clips: Vec<String>,
}

/// The whole batch folder.
#[derive(Clone, Debug, Serialize)]
pub struct BatchStatus {
    /// Every shard, by index.
    pub shards: Vec<ShardStatus>,
    /// Folders under `.partial/`: clips being processed now, or left by killed workers (the
    /// next worker of their shard removes them).
    pub in_progress: usize,
}

impl BatchStatus {
    /// The status of the batch folder `dir`: its clips from `manifest`, else from the
    /// manifest the workers recorded in `dir/batch.json`; in `shard_count` shards, else as
    /// recorded, else 1.
    pub fn read(
        dir: &Path,
        manifest: Option<&Path>,
        shard_count: Option<usize>,
    ) -> Result<BatchStatus, Error> {
        let recorded = BatchRecord::read(dir);
        let manifest_path = match (manifest, &recorded) {
            (Some(m), _) => m.to_owned(),
            (None, Some(r)) => r.manifest.clone(),
            (None, None) if !dir.is_dir() => {
                return Err(Error::NoBatchFolder {
                    dir: dir.to_owned(),
                })
            }
            (None, None) => {
                return Err(Error::NoBatchRecord {
                    dir: dir.to_owned(),
                })
            }
        };
        let clips = manifest::read(&manifest_path)?;
        let shard_count = shard_count
            .or(recorded.as_ref().map(|r| r.shard_count))
            .unwrap_or(1);
        if shard_count == 0 {
            return Err(Error::ZeroShardCount);
        }
        let common = recorded.map(|r| r.options).unwrap_or_default();
        Ok(BatchStatus::of(dir, &clips, shard_count, &common))
    }

    /// The summary of `clips` in `shard_count` shards under `out`.
    pub fn of(out: &Path, clips: &[Clip], shard_count: usize, common: &[String]) -> Self {
        let mut shards: Vec<ShardStatus> = (0..shard_count)
            .map(|shard| ShardStatus {
                shard,
                ..ShardStatus::default()
            })
            .collect();
        for clip in clips {
            let s = &mut shards[shard_of(&clip.id, shard_count)];
            s.clips += 1;
            match state(out, clip, common) {
                State::Done => s.done += 1,
                State::Failed => {
                    s.failed += 1;
                    s.failures
                        .push((clip.id.clone(), failure_reason(out, clip)));
                }
                State::Missing => {
                    s.missing += 1;
                    s.missing_clips.push(clip.id.clone());
                }
            }
        }
        let in_progress = std::fs::read_dir(out.join(PARTIAL)).map_or(0, |d| d.count());
        BatchStatus {
            shards,
            in_progress,
        }
    }

    /// Clips not done nor failed.
    pub fn missing(&self) -> usize {
        self.shards.iter().map(|s| s.missing).sum()
    }

    /// Failed clips.
    pub fn failed(&self) -> usize {
        self.shards.iter().map(|s| s.failed).sum()
    }

    /// The table a person reads.
    pub fn table(&self) -> String {
        let mut t = String::from("shard  clips   done  failed  missing\n");
        let mut total = ShardStatus::default();
        for s in &self.shards {
            t += &format!(
                "{:>5}  {:>5}  {:>5}  {:>6}  {:>7}\n",
                s.shard, s.clips, s.done, s.failed, s.missing
            );
            total.clips += s.clips;
            total.done += s.done;
            total.failed += s.failed;
            total.missing += s.missing;
        }
        t += &format!(
            "  all  {:>5}  {:>5}  {:>6}  {:>7}\n",
            total.clips, total.done, total.failed, total.missing
        );
        for s in &self.shards {
            for (id, why) in &s.failures {
                t += &format!("failed  (shard {}) {id}: {why}\n", s.shard);
            }
        }
        for s in &self.shards {
            for id in s.missing_clips.iter().take(20) {
                t += &format!("missing (shard {}) {id}\n", s.shard);
            }
            if s.missing_clips.len() > 20 {
                t += &format!(
                    "missing (shard {}) … and {} more\n",
                    s.shard,
                    s.missing_clips.len() - 20
                );
            }
        }
        if self.in_progress > 0 {
            t += &format!(
                "{} clip folder(s) in progress under {PARTIAL}/ (or left by a killed worker)\n",
                self.in_progress
            );
        }
        t
    }
}

/// The first line of a failed clip's reason.
fn failure_reason(out: &Path, clip: &Clip) -> String {
    std::fs::read(out.join(&clip.id).join(record::ERROR))
        .ok()
        .and_then(|b| serde_json::from_slice::<record::Failed>(&b).ok())
        .map_or_else(
            || format!("{} does not parse", record::ERROR),
            |f| f.error.lines().next().unwrap_or_default().to_owned(),
        )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_failed_and_the_recorded_manifest() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("out");
        let err = visage::error_chain(&BatchStatus::read(&out, None, None).unwrap_err());
        assert!(err.ends_with("no such folder (a batch folder is the --out of `visage batch`)"));
        std::fs::create_dir_all(&out).unwrap();
        let err = visage::error_chain(&BatchStatus::read(&out, None, None).unwrap_err());
        assert!(err.ends_with("no batch.json (no worker has started there); pass --manifest"));
        let manifest = tmp.path().join("m.txt");
        std::fs::write(&manifest, "a.mp4\nb.mp4\nc.mp4\n").unwrap();
        std::fs::create_dir_all(out.join("b")).unwrap();
        let failed = record::Failed {
            clip: "b".into(),
            input: tmp.path().join("b.mp4"),
            exit_code: 3,
            error: "no face in any frame\nsecond line".into(),
            options: Vec::new(),
            visage_version: "0".into(),
        };
        let json = serde_json::to_string(&failed).unwrap();
        std::fs::write(out.join("b").join(record::ERROR), json).unwrap();
        BatchRecord {
            manifest: manifest.clone(),
            shard_count: 1,
            options: Vec::new(),
        }
        .write(&out)
        .unwrap();
        let s = BatchStatus::read(&out, None, None).unwrap();
        assert_eq!((s.missing(), s.failed(), s.shards.len()), (2, 1, 1));
        let table = s.table();
        assert!(
            table.contains("failed  (shard 0) b: no face in any frame\n"),
            "{table}"
        );
        assert!(table.contains("missing (shard 0) a\n"), "{table}");
        let s = BatchStatus::read(&out, Some(&manifest), Some(3)).unwrap();
        assert_eq!(s.shards.iter().map(|s| s.clips).sum::<usize>(), 3);
        assert!(BatchStatus::read(&out, None, Some(0)).is_err());
    }
}
