//! `visage batch`: a worker over one shard of a manifest of clips, for array jobs on the
//! scheduler a user already has (Slurm, Kubernetes Indexed Jobs, AWS Batch), and
//! `visage batch status`; the worker itself is `visage_batch`'s.
//!
//! Each clip is run as `visage run` would run it (`VisageRun`) into `OUT/.partial/…`, then
//! renamed to `OUT/ID/` with `done.json` (input SHA-256, options, version, output checksums)
//! or `error.json` (why it failed); a clip whose `done.json` is valid is skipped, so a killed
//! or resubmitted worker redoes only what is not done. Exit codes: 0 every clip of the shard
//! done; 3 some failed (the others finished); 2 bad invocation (manifest, shard, options);
//! 130 interrupted.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use clap::{Args, Parser, Subcommand};
use visage_batch::{BatchStatus, BoxError, Clip, ClipError, ClipRunner, Request, ShardRun};

use crate::commands::run::{run_with_stop, RunArgs};
use crate::exit::{self, Failure};
use crate::interrupt;

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

/// Exit code of `batch status` while clips are missing.
const MISSING: u8 = 4;

/// Exit code of a batch or status with failed clips.
const SOME_FAILED: u8 = 3;

/// Runs `visage batch` or `visage batch status`.
pub fn run(args: BatchArgs) -> anyhow::Result<()> {
    if let Some(BatchCommand::Status(s)) = args.command {
        return status(s);
    }
    let (Some(manifest), Some(out)) = (args.manifest, args.out) else {
        anyhow::bail!("visage batch needs a MANIFEST and --out");
    };
    let request = Request {
        manifest,
        out,
        shard_index: args.shard_index,
        shard_count: args.shard_count,
        jobs: usize::from(args.jobs),
        retry_failed: args.retry_failed,
        options: args.options,
    };
    let batch = ShardRun::prepare(request, &VisageRun, |v| std::env::var(v).ok())?;
    let shard = batch.shard;
    eprintln!(
        "visage batch: shard {} of {} (from {}): {} of {} clips{}",
        shard.index,
        shard.count,
        shard.source,
        batch.clips.len(),
        batch.manifest_clips,
        match batch.stale_removed {
            0 => String::new(),
            n => format!("; removed {n} unfinished folder(s) a killed worker left"),
        }
    );
    let stop = interrupt::install(
        "the clip being processed stays in the batch folder's .partial/ and is run again by the \
         next worker; finished clips are kept",
    );
    let summary = batch.run(&VisageRun, &stop, |line| eprintln!("visage batch: {line}"));
    println!("{}", summary.json_line());
    if summary.interrupted {
        return Err(Failure {
            code: interrupt::INTERRUPTED,
            error: anyhow::anyhow!(
                "interrupted: {} clips done in this run; the same command goes on with the \
                 clips not done",
                summary.done
            ),
        }
        .into());
    }
    if summary.failed > 0 {
        return Err(Failure {
            code: SOME_FAILED,
            error: anyhow::anyhow!(
                "{} of {} clips of shard {} failed ({}); each folder's {} says why",
                summary.failed,
                summary.clips,
                shard.index,
                summary.failed_ids.join(", "),
                visage::file_names::BATCH_ERROR
            ),
        }
        .into());
    }
    Ok(())
}

/// Runs `visage batch status`.
fn status(args: StatusArgs) -> anyhow::Result<()> {
    let s = BatchStatus::read(&args.dir, args.manifest.as_deref(), args.shard_count)?;
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

/// A clip run as `visage run INPUT --out OUT --quiet OPTIONS` would run it, in this process.
struct VisageRun;

/// `visage run`'s flags, parsed as the command line would be.
#[derive(Parser)]
#[command(name = "visage run", no_binary_name = false)]
struct RunLine {
    #[command(flatten)]
    run: RunArgs,
}

impl VisageRun {
    /// The `visage run` arguments of `clip` into `out` with `options`.
    fn args(clip: &Clip, out: &Path, options: &[String]) -> anyhow::Result<RunArgs> {
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
}

impl ClipRunner for VisageRun {
    fn check(&self, clip: &Clip, options: &[String]) -> Result<(), BoxError> {
        VisageRun::args(clip, Path::new("out"), options)?;
        Ok(())
    }

    fn run(
        &self,
        clip: &Clip,
        out: &Path,
        options: &[String],
        stop: &Arc<AtomicBool>,
    ) -> Result<(), ClipError> {
        let clip_error = |e: anyhow::Error| match exit::code_of(&e) {
            interrupt::INTERRUPTED => ClipError::Interrupted,
            exit_code => ClipError::Failed {
                exit_code,
                error: visage::error_chain(e.as_ref()),
            },
        };
        let args = VisageRun::args(clip, out, options).map_err(clip_error)?;
        run_with_stop(args, stop).map_err(clip_error)
    }
}
