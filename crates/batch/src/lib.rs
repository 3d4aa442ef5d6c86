//! The batch worker: one shard of a manifest of clips, for array jobs on the scheduler a user
//! already has (Slurm, Kubernetes Indexed Jobs, AWS Batch), and the status of a batch folder.
//!
//! [`ShardRun::prepare`] reads the [`manifest`], takes the clips of its [`Shard`]
//! (`FNV-1a-64(id) mod N`), checks every clip's options and records the batch in
//! `OUT/batch.json` ([`BatchRecord`]); [`ShardRun::run`] then runs each clip as `visage run`
//! would, into `OUT/.partial/…`, and renames the folder to `OUT/ID/` with `done.json`
//! (input SHA-256, options, version, output checksums) or `error.json` (why it failed): see
//! [`record`]. A clip whose `done.json` is valid is skipped, so a killed or resubmitted worker
//! redoes only what is not done. [`BatchStatus`] counts done, failed and missing clips per
//! shard.
//!
//! How one clip runs is the caller's ([`ClipRunner`]): the `visage` binary parses `visage
//! run`'s flags and runs its pipeline; this crate knows nothing of the command line. Exit
//! codes are the caller's too; the [`Summary`] and the errors carry what they need.
//! `docs/batch.md` describes the manifest, the shard rule and the folder for users.

#![forbid(unsafe_code)]

mod batch_record;
mod clip_runner;
mod error;
pub mod manifest;
pub mod record;
mod shard;
mod shard_run;
mod status;
mod summary;
mod worker;

pub use batch_record::BatchRecord;
pub use clip_runner::{check_options, ClipError, ClipRunner, RESERVED_FLAGS};
pub use error::{BoxError, Error, IdError, ManifestError};
pub use manifest::Clip;
pub use shard::{fnv1a64, shard_of, Shard};
pub use shard_run::{Request, ShardRun};
pub use status::{BatchStatus, ShardStatus, State};
pub use summary::Summary;
pub use worker::{Outcome, Worker, PARTIAL};
