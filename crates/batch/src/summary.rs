//! What one worker did with its shard: the counts it prints as one JSON line when it ends,
//! and what its exit code is decided from (interrupted, failed clips).

use crate::manifest::Clip;
use crate::shard::Shard;
use crate::worker::Outcome;

/// The end of a worker's run over its shard.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// The worker's shard.
    pub shard: Shard,
    /// The shard's clips.
    pub clips: usize,
    /// Clips processed now.
    pub done: usize,
    /// Clips done before (a valid `done.json`).
    pub skipped: usize,
    /// Clips failed, now or before.
    pub failed: usize,
    /// Of `failed`, those kept from an earlier run (without `--retry-failed`).
    pub failed_before: usize,
    /// Clips not started (the worker was stopped).
    pub not_run: usize,
    /// Frames processed now, over the clips done now.
    pub frames: u64,
    /// Wall-clock seconds since the worker started.
    pub seconds: f64,
    /// Clips run at once.
    pub jobs: usize,
    /// The CPU cores the worker could use.
    pub cores: usize,
    /// The failed clips' ids, in manifest order.
    pub failed_ids: Vec<String>,
    /// Stopped by the stop flag: the clips not done are left for the next worker.
    pub interrupted: bool,
}

impl Summary {
    /// The summary of `results` (indices into `clips`, the shard's, with their outcomes).
    pub(crate) fn of(
        shard: Shard,
        clips: &[Clip],
        results: &[(usize, Outcome)],
        jobs: usize,
        seconds: f64,
        stopped: bool,
    ) -> Summary {
        let count = |f: &dyn Fn(&Outcome) -> bool| results.iter().filter(|(_, o)| f(o)).count();
        let frames = results
            .iter()
            .map(|(_, o)| match o {
                Outcome::Done { frames, .. } => *frames,
                _ => 0,
            })
            .sum();
        Summary {
            shard,
            clips: clips.len(),
            done: count(&|o| matches!(o, Outcome::Done { .. })),
            skipped: count(&|o| *o == Outcome::Skipped),
            failed: count(&|o| matches!(o, Outcome::Failed { .. })),
            failed_before: count(&|o| *o == Outcome::Failed { now: false }),
            not_run: clips.len() - results.len(),
            frames,
            seconds,
            jobs,
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            failed_ids: results
                .iter()
                .filter(|(_, o)| matches!(o, Outcome::Failed { .. }))
                .map(|(i, _)| clips[*i].id.clone())
                .collect(),
            interrupted: stopped || results.iter().any(|(_, o)| *o == Outcome::Interrupted),
        }
    }

    /// Frames per hour and core: the throughput figure of `docs/batch.md`.
    pub fn frames_per_hour_per_core(&self) -> f64 {
        self.frames as f64 / self.seconds * 3600.0 / self.cores as f64
    }

    /// The one JSON line a worker prints on stdout (keys in alphabetical order).
    pub fn json_line(&self) -> String {
        serde_json::json!({
            "shard": { "index": self.shard.index, "count": self.shard.count },
            "clips": self.clips,
            "done": self.done,
            "skipped": self.skipped,
            "failed": self.failed,
            "failed_before": self.failed_before,
            "not_run": self.not_run,
            "frames": self.frames,
            "seconds": self.seconds,
            "jobs": self.jobs,
            "cores": self.cores,
            "frames_per_hour_per_core": self.frames_per_hour_per_core(),
        })
        .to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_the_json_line() {
        let clips: Vec<Clip> = ["a", "b", "c", "d"]
            .iter()
            .enumerate()
            .map(|(i, id)| Clip {
                line: i + 1,
                id: id.to_string(),
                input: format!("{id}.mp4").into(),
                options: Vec::new(),
            })
            .collect();
        let results = [
            (
                0,
                Outcome::Done {
                    frames: 10,
                    meshed: 9,
                },
            ),
            (1, Outcome::Failed { now: false }),
            (2, Outcome::Skipped),
        ];
        let shard = Shard {
            index: 1,
            count: 2,
            source: "default",
        };
        let s = Summary::of(shard, &clips, &results, 1, 2.0, false);
        assert_eq!((s.done, s.skipped, s.failed, s.failed_before), (1, 1, 1, 1));
        assert_eq!((s.not_run, s.frames, s.interrupted), (1, 10, false));
        assert_eq!(s.failed_ids, ["b"]);
        let line = s.json_line();
        assert!(
            line.starts_with(r#"{"shard":{"index":1,"count":2},"clips":4,"done":1,"skipped":1,"#),
            "{line}"
        );
        assert!(line.contains(r#""jobs":1,"cores":"#), "{line}");
        assert!(Summary::of(shard, &clips, &results, 1, 2.0, true).interrupted);
    }
}
