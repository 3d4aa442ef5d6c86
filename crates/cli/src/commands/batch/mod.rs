//! `visage batch`: a worker over one shard of a manifest of clips, for array jobs on the
//! scheduler a user already has (Slurm, Kubernetes Indexed Jobs, AWS Batch), and
//! `visage batch status`.
//!
//! Each clip is run as `visage run` would run it into `OUT/.partial/…`, then renamed to
//! `OUT/ID/` with `done.json` (input SHA-256, options, version, output checksums) or
//! `error.json` (why it failed); a clip whose `done.json` is valid is skipped, so a killed or
//! resubmitted worker redoes only what is not done. Exit codes: 0 every clip of the shard
//! done; 3 some failed (the others finished); 2 bad invocation (manifest, shard, options);
//! 130 interrupted.

mod manifest;
mod record;
mod shard;
mod status;
mod worker;

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::{Args, Subcommand};
use serde::{Deserialize, Serialize};

use crate::exit::Failure;
use crate::interrupt;
use worker::{Outcome, Worker};

/// Arguments of `visage batch`.
#[derive(Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct BatchArgs {
    #[command(subcommand)]
    pub command: Option<BatchCommand>,
    /// The clips: one input per line (PATH, or PATH, a tab and INTRINSICS.json; `#` comments), or
    /// JSON Lines ({"input": PATH, "intrinsics": FILE, "id": NAME, "options": [FLAG…]}).
    /// Relative paths are relative to the manifest's folder. A clip's id (the path without
    /// its extension, or "id") names its output folder OUT/ID/.
    #[arg(required = true)]
    pub manifest: Option<PathBuf>,
    /// The batch folder: OUT/ID/ per clip.
    #[arg(long, required = true)]
    pub out: Option<PathBuf>,
    /// This worker's shard, from 0 (default: the scheduler's array index —
    /// $SLURM_ARRAY_TASK_ID, $JOB_COMPLETION_INDEX, $AWS_BATCH_JOB_ARRAY_INDEX — or
    /// $VISAGE_SHARD_INDEX, else 0). A clip's shard is FNV-1a-64(ID) mod the shard count.
    #[arg(long, requires = "shard_count")]
    pub shard_index: Option<usize>,
    /// The number of shards (default: $SLURM_ARRAY_TASK_COUNT, $AWS_BATCH_JOB_ARRAY_SIZE or
    /// $VISAGE_SHARD_COUNT, else 1).
    #[arg(long)]
    pub shard_count: Option<usize>,
    /// Clips processed at once by this worker.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..))]
    pub jobs: u16,
    /// Run clips again that failed before (their error.json); without it they are kept.
    #[arg(long)]
    pub retry_failed: bool,
    /// `visage run` options for every clip (after a `--`), e.g. `-- --glb --fov-deg 50`.
    #[arg(last = true, value_name = "RUN_OPTION")]
    pub options: Vec<String>,
}

#[derive(Subcommand, Debug)]
pub enum BatchCommand {
    /// Done, failed and missing clips per shard of a batch folder
    ///
    /// Exit codes: 0 every clip done; 3 every clip finished but some failed; 4 some clips
    /// are missing (not yet run, running, or killed); 2 bad invocation.
    Status(StatusArgs),
}

/// Arguments of `visage batch status`.
#[derive(Args, Debug)]
pub struct StatusArgs {
    /// The batch folder.
    pub dir: PathBuf,
    /// The manifest (default: the one the batch's workers recorded in DIR/batch.json).
    #[arg(long)]
    pub manifest: Option<PathBuf>,
    /// The number of shards (default: as recorded in DIR/batch.json).
    #[arg(long)]
    pub shard_count: Option<usize>,
    /// JSON instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// What workers record in `OUT/batch.json`, for `visage batch status`.
#[derive(Serialize, Deserialize)]
struct BatchRecord {
    manifest: PathBuf,
    shard_count: usize,
    options: Vec<String>,
}

/// Exit code of `batch status` while clips are missing.
const MISSING: u8 = 4;

/// Exit code of a batch or status with failed clips.
const SOME_FAILED: u8 = 3;

/// Runs `visage batch` or `visage batch status`.
pub fn run(args: BatchArgs) -> anyhow::Result<()> {
    if let Some(BatchCommand::Status(s)) = args.command {
        return status(s);
    }
    let (Some(manifest_path), Some(out)) = (args.manifest, args.out) else {
        anyhow::bail!("visage batch needs a MANIFEST and --out");
    };
    let started = Instant::now();
    let clips = manifest::read(&manifest_path)?;
    let shard = shard::resolve(args.shard_index, args.shard_count, |v| {
        std::env::var(v).ok()
    })?;
    let mine: Vec<manifest::Clip> = clips
        .iter()
        .filter(|c| shard.owns(&c.id))
        .cloned()
        .collect();
    worker::check_options(&mine, &args.options)?;
    std::fs::create_dir_all(&out)
        .with_context(|| format!("{}: cannot create the batch folder", out.display()))?;
    let manifest_abs = std::fs::canonicalize(&manifest_path).unwrap_or(manifest_path.clone());
    record_batch(
        &out,
        &BatchRecord {
            manifest: manifest_abs,
            shard_count: shard.count,
            options: args.options.clone(),
        },
    )?;
    let w = Worker {
        out: out.clone(),
        common: args.options,
        retry_failed: args.retry_failed,
    };
    let stale = w.clear_stale(&mine)?;
    eprintln!(
        "visage batch: shard {} of {} (from {}): {} of {} clips{}",
        shard.index,
        shard.count,
        shard.source,
        mine.len(),
        clips.len(),
        match stale {
            0 => String::new(),
            n => format!("; removed {n} unfinished folder(s) a killed worker left"),
        }
    );
    let stop = interrupt::install();
    let results = w.run_all(&mine, usize::from(args.jobs), &stop, |line| {
        eprintln!("visage batch: {line}")
    });
    // The partial folder goes when it is empty (other shards may still be working in it).
    std::fs::remove_dir(out.join(worker::PARTIAL)).ok();
    let count = |f: &dyn Fn(&Outcome) -> bool| results.iter().filter(|(_, o)| f(o)).count();
    let done = count(&|o| matches!(o, Outcome::Done { .. }));
    let skipped = count(&|o| *o == Outcome::Skipped);
    let failed = count(&|o| matches!(o, Outcome::Failed { .. }));
    let failed_before = count(&|o| *o == Outcome::Failed { now: false });
    let frames: u64 = results
        .iter()
        .map(|(_, o)| match o {
            Outcome::Done { frames, .. } => *frames,
            _ => 0,
        })
        .sum();
    let seconds = started.elapsed().as_secs_f64();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let summary = serde_json::json!({
        "shard": { "index": shard.index, "count": shard.count },
        "clips": mine.len(),
        "done": done,
        "skipped": skipped,
        "failed": failed,
        "failed_before": failed_before,
        "not_run": mine.len() - results.len(),
        "frames": frames,
        "seconds": seconds,
        "jobs": args.jobs,
        "cores": cores,
        "frames_per_hour_per_core": frames as f64 / seconds * 3600.0 / cores as f64,
    });
    println!("{summary}");
    if stop.load(std::sync::atomic::Ordering::SeqCst)
        || results.iter().any(|(_, o)| *o == Outcome::Interrupted)
    {
        return Err(Failure {
            code: interrupt::INTERRUPTED,
            error: anyhow::anyhow!(
                "interrupted: {done} clips done in this run; the same command goes on with the \
                 clips not done"
            ),
        }
        .into());
    }
    if failed > 0 {
        let ids: Vec<&str> = results
            .iter()
            .filter(|(_, o)| matches!(o, Outcome::Failed { .. }))
            .map(|(i, _)| mine[*i].id.as_str())
            .collect();
        return Err(Failure {
            code: SOME_FAILED,
            error: anyhow::anyhow!(
                "{failed} of {} clips of shard {} failed ({}); each folder's error.json says why",
                mine.len(),
                shard.index,
                ids.join(", ")
            ),
        }
        .into());
    }
    Ok(())
}

/// Writes `OUT/batch.json` through a temporary file of this process's own (the shards of a
/// batch start together and write the same record).
fn record_batch(out: &std::path::Path, record: &BatchRecord) -> anyhow::Result<()> {
    let path = out.join("batch.json");
    let tmp = out.join(format!(".batch.json.{}.tmp", std::process::id()));
    std::fs::write(&tmp, serde_json::to_string_pretty(record)?)
        .with_context(|| format!("{}: cannot write", tmp.display()))?;
    std::fs::rename(&tmp, &path).with_context(|| format!("{}: cannot write", path.display()))
}

/// Runs `visage batch status`.
fn status(args: StatusArgs) -> anyhow::Result<()> {
    let recorded: Option<BatchRecord> = std::fs::read(args.dir.join("batch.json"))
        .ok()
        .and_then(|b| serde_json::from_slice(&b).ok());
    let manifest_path = match (&args.manifest, &recorded) {
        (Some(m), _) => m.clone(),
        (None, Some(r)) => r.manifest.clone(),
        (None, None) => anyhow::bail!(
            "{}: no batch.json (no worker has started there); pass --manifest",
            args.dir.display()
        ),
    };
    let clips = manifest::read(&manifest_path)?;
    let shard_count = args
        .shard_count
        .or(recorded.as_ref().map(|r| r.shard_count))
        .unwrap_or(1);
    if shard_count == 0 {
        anyhow::bail!("--shard-count must be at least 1");
    }
    let common = recorded.map(|r| r.options).unwrap_or_default();
    let s = status::BatchStatus::of(&args.dir, &clips, shard_count, &common);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&s)?);
    } else {
        print!("{}", s.table());
    }
    let code = match (s.missing(), s.failed()) {
        (0, 0) => return Ok(()),
        (0, _) => SOME_FAILED,
        _ => MISSING,
    };
    Err(Failure {
        code,
        error: anyhow::anyhow!(
            "{}: {} clips missing, {} failed",
            args.dir.display(),
            s.missing(),
            s.failed()
        ),
    }
    .into())
}
