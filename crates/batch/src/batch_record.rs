//! `OUT/batch.json`: what the workers of a batch were given (the manifest, the shard count,
//! the common options), so that `visage batch status OUT` needs no arguments.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use visage_run_folder::file_names;

use crate::error::Error;

/// The record's file name in the batch folder.
const FILE_NAME: &str = file_names::BATCH;

/// What workers record in `OUT/batch.json`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct BatchRecord {
    /// The manifest, made absolute where it could be.
    pub manifest: PathBuf,
    /// The number of shards.
    pub shard_count: usize,
    /// The options for every clip (after each clip's own).
    pub options: Vec<String>,
}

impl BatchRecord {
    /// Writes `out/batch.json` through a temporary file of this process's own (the shards of
    /// a batch start together and write the same record).
    pub fn write(&self, out: &Path) -> Result<(), Error> {
        let path = out.join(FILE_NAME);
        let tmp = out.join(format!(".{FILE_NAME}.{}.tmp", std::process::id()));
        let text = serde_json::to_string_pretty(self).map_err(Error::Json)?;
        std::fs::write(&tmp, text).map_err(|source| Error::Write {
            path: tmp.clone(),
            source,
        })?;
        std::fs::rename(&tmp, &path).map_err(|source| Error::Write { path, source })
    }

    /// The record in the batch folder `out`; None when there is none or it does not parse.
    pub fn read(out: &Path) -> Option<BatchRecord> {
        std::fs::read(out.join(FILE_NAME))
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_then_read_back() {
        let tmp = tempfile::tempdir().unwrap();
        assert_eq!(BatchRecord::read(tmp.path()), None);
        let record = BatchRecord {
            manifest: "/data/m.jsonl".into(),
            shard_count: 4,
            options: vec!["--glb".into()],
        };
        record.write(tmp.path()).unwrap();
        record.write(tmp.path()).unwrap();
        assert_eq!(BatchRecord::read(tmp.path()), Some(record));
        let names: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "no temporary file is left");
    }
}
