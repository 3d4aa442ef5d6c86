//! What a clip's folder says about it: `done.json` (what was made from what, with checksums)
//! or `error.json` (why it failed), and the checks that decide whether a clip is done.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use visage_run_folder::file_names;

use crate::error::Error;

/// The record of a finished clip.
pub const DONE: &str = file_names::BATCH_DONE;
/// The record of a failed clip.
pub const ERROR: &str = file_names::BATCH_ERROR;

/// An input or output file: size and SHA-256.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileSum {
    /// The size in bytes.
    pub bytes: u64,
    /// The SHA-256 digest, 64 lowercase hex digits.
    pub sha256: String,
}

impl FileSum {
    /// Reads `path` through once.
    pub fn of(path: &Path) -> Result<Self, Error> {
        let (bytes, sha256) = visage_run_folder::sha256_of(path).map_err(|e| match e {
            visage_run_folder::RunFolderError::Read { path, source } => {
                Error::Read { path, source }
            }
            other => Error::Record(Box::new(other)),
        })?;
        Ok(FileSum { bytes, sha256 })
    }
}

/// `done.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Done {
    /// The clip's id (its folder's path under the batch folder).
    pub clip: String,
    /// The input as the manifest resolved it.
    pub input: PathBuf,
    /// The input's size and SHA-256.
    pub input_file: FileSum,
    /// Seconds since the Unix epoch of the input's modification time when it was hashed.
    pub input_modified_s: Option<f64>,
    /// The `visage run` options the clip was processed with (the manifest's, then the batch's).
    pub options: Vec<String>,
    /// The version of visage that made the outputs.
    pub visage_version: String,
    /// Frames processed and frames meshed (metrics.json's summary).
    pub frames: u64,
    pub meshed: u64,
    /// Wall-clock seconds the clip took.
    pub seconds: f64,
    /// Every file of the folder but this record, by path relative to it.
    pub outputs: std::collections::BTreeMap<String, FileSum>,
}

/// `error.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Failed {
    /// The clip's id.
    pub clip: String,
    /// The input as the manifest resolved it.
    pub input: PathBuf,
    /// The exit code `visage run` would have given: 2 bad input, 3 no face, 1 internal.
    pub exit_code: u8,
    /// What went wrong, the whole chain of causes.
    pub error: String,
    /// The `visage run` options the clip was run with.
    pub options: Vec<String>,
    /// The version of visage that ran it.
    pub visage_version: String,
}

/// The input's modification time, seconds since the Unix epoch.
pub fn modified_s(path: &Path) -> Option<f64> {
    let t = std::fs::metadata(path).ok()?.modified().ok()?;
    Some(t.duration_since(std::time::UNIX_EPOCH).ok()?.as_secs_f64())
}

/// Every file under `dir` but the records, by `/`-separated path relative to it, with sums.
pub fn output_sums(dir: &Path) -> Result<std::collections::BTreeMap<String, FileSum>, Error> {
    let mut sums = std::collections::BTreeMap::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        let entries = std::fs::read_dir(&d).map_err(|source| Error::List {
            path: d.clone(),
            source,
        })?;
        for entry in entries {
            let path = entry.map_err(Error::Io)?.path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            let rel = path.strip_prefix(dir).expect("under dir");
            let rel = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy())
                .collect::<Vec<_>>()
                .join("/");
            if rel != DONE && rel != ERROR {
                sums.insert(rel, FileSum::of(&path)?);
            }
        }
    }
    Ok(sums)
}

/// Why a clip's folder does not count as done for `input` with `options` (None: it does).
///
/// The record must parse, name the same options and an input with the same size and SHA-256
/// (the hash is not recomputed while size and modification time are unchanged), and every
/// output it lists must be there with its size.
pub fn not_done(folder: &Path, input: &Path, options: &[String]) -> Option<String> {
    let text = match std::fs::read_to_string(folder.join(DONE)) {
        Ok(t) => t,
        Err(_) => return Some(format!("no {DONE}")),
    };
    let done: Done = match serde_json::from_str(&text) {
        Ok(d) => d,
        Err(e) => return Some(format!("{DONE} does not parse ({e})")),
    };
    if done.options != options {
        return Some(format!(
            "done with other options ({:?}, now {options:?})",
            done.options
        ));
    }
    let size = std::fs::metadata(input).map(|m| m.len()).ok();
    if size != Some(done.input_file.bytes) {
        return Some("the input changed size".into());
    }
    let same_time = match (done.input_modified_s, modified_s(input)) {
        (Some(a), Some(b)) => a == b,
        _ => false,
    };
    if !same_time {
        match FileSum::of(input) {
            Ok(sum) if sum == done.input_file => {}
            _ => return Some("the input changed (SHA-256)".into()),
        }
    }
    for (rel, sum) in &done.outputs {
        let len = std::fs::metadata(folder.join(rel)).map(|m| m.len()).ok();
        if len != Some(sum.bytes) {
            return Some(format!("its output {rel} is missing or has changed"));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_and_the_done_check() {
        let tmp = tempfile::tempdir().unwrap();
        let input = tmp.path().join("in.bin");
        std::fs::write(&input, b"abc").unwrap();
        let sum = FileSum::of(&input).unwrap();
        assert_eq!(sum.bytes, 3);
        assert_eq!(
            sum.sha256,
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        let folder = tmp.path().join("clip");
        std::fs::create_dir_all(folder.join("sub")).unwrap();
        std::fs::write(folder.join("sub/a.txt"), b"hello").unwrap();
        std::fs::write(folder.join("b.txt"), b"x").unwrap();
        let outputs = output_sums(&folder).unwrap();
        assert_eq!(outputs.keys().collect::<Vec<_>>(), ["b.txt", "sub/a.txt"]);
        assert_eq!(not_done(&folder, &input, &[]).unwrap(), "no done.json");
        let done = Done {
            clip: "clip".into(),
            input: input.clone(),
            input_file: sum,
            input_modified_s: modified_s(&input),
            options: vec!["--fov-deg".into(), "50".into()],
            visage_version: "0".into(),
            frames: 1,
            meshed: 1,
            seconds: 0.1,
            outputs,
        };
        std::fs::write(folder.join(DONE), serde_json::to_string(&done).unwrap()).unwrap();
        let opts = done.options.clone();
        assert_eq!(not_done(&folder, &input, &opts), None);
        assert!(not_done(&folder, &input, &[])
            .unwrap()
            .contains("other options"));
        std::fs::write(folder.join("b.txt"), b"xy").unwrap();
        assert!(not_done(&folder, &input, &opts).unwrap().contains("b.txt"));
        std::fs::write(folder.join("b.txt"), b"x").unwrap();
        std::fs::write(&input, b"abd").unwrap();
        // Same size; a new modification time (set, as two writes may share a clock tick).
        std::fs::File::options()
            .write(true)
            .open(&input)
            .unwrap()
            .set_modified(std::time::UNIX_EPOCH + std::time::Duration::from_secs(1000))
            .unwrap();
        assert!(not_done(&folder, &input, &opts)
            .unwrap()
            .contains("SHA-256"));
    }
}
