//! The batch's errors. Each names the file, manifest line or variable at fault; the causes
//! hang below as sources (`visage::error_chain` joins them with `: `).

use std::path::PathBuf;

/// A cause supplied by the caller (a `ClipRunner`'s option check).
pub type BoxError = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Errors of the batch worker and of a batch folder's status.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The manifest file could not be read.
    #[error("{}: cannot read the manifest", path.display())]
    ReadManifest {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The manifest was read, but a line of it is wrong.
    #[error("{}: not a usable manifest", path.display())]
    Manifest {
        path: PathBuf,
        source: ManifestError,
    },
    /// A scheduler variable that should be a shard index or count is not a number.
    #[error("${name} = {value:?} is not a whole number")]
    NotANumber {
        name: String,
        value: String,
        source: std::num::ParseIntError,
    },
    /// `--shard-index` without `--shard-count`.
    #[error("--shard-index needs --shard-count")]
    IndexWithoutCount,
    /// A Slurm array task without its array's size.
    #[error("$SLURM_ARRAY_TASK_ID is set but $SLURM_ARRAY_TASK_COUNT is not")]
    SlurmCountMissing,
    /// A Slurm task id below the array's first.
    #[error("$SLURM_ARRAY_TASK_ID = {id} is below $SLURM_ARRAY_TASK_MIN = {min}")]
    SlurmIdBelowMin { id: usize, min: usize },
    /// A Kubernetes Indexed Job's pod without the shard count.
    #[error(
        "$JOB_COMPLETION_INDEX is set (a Kubernetes Indexed Job) but the shard count is not: \
         pass --shard-count or set $VISAGE_SHARD_COUNT to the job's completions"
    )]
    KubernetesCountMissing,
    /// An AWS Batch array child without the array's size.
    #[error("$AWS_BATCH_JOB_ARRAY_INDEX is set but $AWS_BATCH_JOB_ARRAY_SIZE is not")]
    AwsCountMissing,
    /// `$VISAGE_SHARD_INDEX` without a count.
    #[error("$VISAGE_SHARD_INDEX is set but neither --shard-count nor $VISAGE_SHARD_COUNT")]
    VisageCountMissing,
    /// A shard count of 0; `from` says where it came from.
    #[error("the shard count is 0 (from {from}); it must be at least 1")]
    ZeroShards { from: &'static str },
    /// A shard index not below the count.
    #[error("shard index {index} (from {from}) is not below the shard count {count}; indices run from 0")]
    IndexNotBelowCount {
        index: usize,
        from: &'static str,
        count: usize,
    },
    /// `visage batch status --shard-count 0`.
    #[error("--shard-count must be at least 1")]
    ZeroShardCount,
    /// A clip's options cannot be run (a typo, a flag the batch sets itself).
    #[error("manifest line {line} ({id}): bad options")]
    BadOptions {
        line: usize,
        id: String,
        source: BoxError,
    },
    /// A clip's options name a flag the batch sets itself (`RESERVED_FLAGS`).
    #[error("{flag} is set by `visage batch` itself (each clip goes to OUT/ID)")]
    ReservedFlag { flag: String },
    /// `batch status` on a folder no worker has recorded, without `--manifest`.
    #[error("{}: no batch.json (no worker has started there); pass --manifest", dir.display())]
    NoBatchRecord { dir: PathBuf },
    /// `batch status` of a folder that does not exist.
    #[error(
        "{}: no such folder (a batch folder is the --out of `visage batch`)",
        dir.display()
    )]
    NoBatchFolder { dir: PathBuf },
    /// The batch folder could not be created.
    #[error("{}: cannot create the batch folder", path.display())]
    CreateBatchFolder {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A file could not be read.
    #[error("{}: cannot read", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A folder could not be listed.
    #[error("{}: cannot list", path.display())]
    List {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A file could not be written or renamed into place.
    #[error("{}: cannot write", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A folder could not be created.
    #[error("{}: cannot create", path.display())]
    Create {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A folder could not be removed.
    #[error("{}: cannot remove", path.display())]
    Remove {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A clip's old folder could not be moved aside for the new one.
    #[error("{}: cannot move aside", path.display())]
    MoveAside {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A clip's temporary folder could not be renamed into place.
    #[error("cannot rename {} to {}", from.display(), to.display())]
    Rename {
        from: PathBuf,
        to: PathBuf,
        source: std::io::Error,
    },
    /// A folder's entry could not be read while listing it.
    #[error(transparent)]
    Io(std::io::Error),
    /// A record could not be turned into JSON (a path that is not UTF-8).
    #[error(transparent)]
    Json(serde_json::Error),
    /// A clip's record could not be written.
    #[error(transparent)]
    Record(Box<visage_run_folder::RunFolderError>),
}

/// What is wrong with a line of the manifest; `line` is 1-based.
#[derive(Debug, thiserror::Error)]
pub enum ManifestError {
    /// A JSON Lines entry that does not parse.
    #[error("line {line}: not a JSON object with \"input\"")]
    NotJson {
        line: usize,
        source: serde_json::Error,
    },
    /// A plain line with a third field.
    #[error("line {line}: {extra:?} after the intrinsics (a line is PATH or PATH<TAB>INTRINSICS)")]
    ExtraField { line: usize, extra: String },
    /// An empty input path.
    #[error("line {line}: no input path")]
    NoInput { line: usize },
    /// An id that cannot name a folder under the batch folder.
    #[error("line {line}: {id:?} cannot name a folder")]
    BadId {
        line: usize,
        id: String,
        source: IdError,
    },
    /// Two lines naming one clip (one output folder).
    #[error(
        "lines {first} and {line} both name the clip {id:?} (their output folder); give one \
         an \"id\" (JSON Lines) or rename a file"
    )]
    DuplicateId {
        first: usize,
        line: usize,
        id: String,
    },
    /// Nothing but comments and blank lines.
    #[error("no clips (one input path per line)")]
    NoClips,
}

/// Why a clip id cannot name a folder.
#[derive(Debug, thiserror::Error)]
pub enum IdError {
    #[error("an empty name")]
    Empty,
    #[error("{part:?} is not a plain folder name (the id is a relative path of names that do not start with a dot)")]
    NotPlain { part: String },
}
