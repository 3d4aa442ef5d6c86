//! Writing files so that a reader never sees a half-written one.

use std::path::{Path, PathBuf};

use crate::RunFolderError as Error;

/// Calls `write` on a temporary sibling of `path` (`<name>.tmp`) and renames it to `path` once
/// `write` succeeded; on failure the temporary file is removed.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), Error>,
) -> Result<(), Error> {
    let tmp = tmp_path(path);
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    std::fs::rename(&tmp, path).map_err(|source| Error::Write {
        path: path.to_owned(),
        source,
    })
}

/// `path` with `.tmp` appended to its file name.
pub fn tmp_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(crate::file_names::TMP_SUFFIX);
    path.with_file_name(name)
}

/// Writes `value` as pretty JSON to `path`, atomically.
pub fn write_json_atomically(path: &Path, value: &impl serde::Serialize) -> Result<(), Error> {
    let text = serde_json::to_string_pretty(value).map_err(|e| Error::Write {
        path: path.to_owned(),
        source: e.into(),
    })?;
    write_atomically(path, |tmp| {
        std::fs::write(tmp, &text).map_err(|source| Error::Write {
            path: tmp.to_owned(),
            source,
        })
    })
}
