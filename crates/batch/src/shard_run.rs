//! One worker's invocation: [`ShardRun::prepare`] does everything that can refuse the
//! invocation before any clip runs (the manifest, the shard, every clip's options, the batch
//! folder and its `batch.json`, what a killed worker of the shard left); [`ShardRun::run`]
//! runs the shard's clips and sums up.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use crate::batch_record::BatchRecord;
use crate::clip_runner::{check_options, ClipRunner};
use crate::error::Error;
use crate::manifest::{self, Clip};
use crate::shard::Shard;
use crate::summary::Summary;
use crate::worker::{Worker, PARTIAL};

/// What a worker is asked to do (`visage batch`'s flags).
#[derive(Clone, Debug, Default)]
pub struct Request {
    /// The manifest file.
    pub manifest: PathBuf,
    /// The batch folder: `OUT/ID/` per clip.
    pub out: PathBuf,
    /// This worker's shard, from 0; None: from the scheduler's variables.
    pub shard_index: Option<usize>,
    /// The number of shards; None: from the scheduler's variables, else 1.
    pub shard_count: Option<usize>,
    /// Clips run at once (0 is taken as 1).
    pub jobs: usize,
    /// Run clips again that failed before; else they are kept.
    pub retry_failed: bool,
    /// Options for every clip, after the clip's own.
    pub options: Vec<String>,
}

/// A worker ready to run its shard.
#[derive(Debug)]
pub struct ShardRun {
    /// The worker's shard.
    pub shard: Shard,
    /// The shard's clips, in manifest order.
    pub clips: Vec<Clip>,
    /// The clips of the whole manifest.
    pub manifest_clips: usize,
    /// Temporary folders of killed workers of this shard, removed.
    pub stale_removed: usize,
    worker: Worker,
    jobs: usize,
    started: Instant,
}

impl ShardRun {
    /// Reads the manifest, resolves the shard (`var` reads the scheduler's variables),
    /// checks every clip's options with `runner`, creates the batch folder, records the batch
    /// in `OUT/batch.json` and removes what killed workers of this shard left. Nothing is
    /// written before the checks pass.
    pub fn prepare(
        request: Request,
        runner: &impl ClipRunner,
        var: impl Fn(&str) -> Option<String>,
    ) -> Result<ShardRun, Error> {
        let started = Instant::now();
        let all = manifest::read(&request.manifest)?;
        let shard = Shard::resolve(request.shard_index, request.shard_count, var)?;
        let clips: Vec<Clip> = all.iter().filter(|c| shard.owns(&c.id)).cloned().collect();
        check_options(&clips, &request.options, runner)?;
        let out = request.out;
        std::fs::create_dir_all(&out).map_err(|source| Error::CreateBatchFolder {
            path: out.clone(),
            source,
        })?;
        let manifest = std::fs::canonicalize(&request.manifest).unwrap_or(request.manifest);
        BatchRecord {
            manifest,
            shard_count: shard.count,
            options: request.options.clone(),
        }
        .write(&out)?;
        let worker = Worker {
            out,
            common: request.options,
            retry_failed: request.retry_failed,
        };
        let stale_removed = worker.clear_stale(&clips)?;
        Ok(ShardRun {
            shard,
            manifest_clips: all.len(),
            clips,
            stale_removed,
            worker,
            jobs: request.jobs.max(1),
            started,
        })
    }

    /// Runs the shard's clips with `runner` until `stop` turns true; `log` gets a line per
    /// clip.
    pub fn run(
        &self,
        runner: &impl ClipRunner,
        stop: &Arc<AtomicBool>,
        log: impl Fn(&str) + Sync,
    ) -> Summary {
        let results = self
            .worker
            .run_all(&self.clips, self.jobs, runner, stop, log);
        // The partial folder goes when it is empty (other shards may still be working in it).
        std::fs::remove_dir(self.worker.out.join(PARTIAL)).ok();
        Summary::of(
            self.shard,
            &self.clips,
            &results,
            self.jobs,
            self.started.elapsed().as_secs_f64(),
            stop.load(Ordering::SeqCst),
        )
    }
}
