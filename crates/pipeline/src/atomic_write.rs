//! Writing files so that a reader never sees a half-written one.

use std::path::{Path, PathBuf};

use crate::PipelineError;

/// Calls `write` on a temporary sibling of `path` (`<name>.tmp`) and renames it to `path` once
/// `write` succeeded; on failure the temporary file is removed.
pub fn write_atomically<E>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), PipelineError>
where
    PipelineError: From<E>,
{
    let mut tmp: PathBuf = path.to_owned();
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".tmp");
    tmp.set_file_name(name);
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(e.into());
    }
    std::fs::rename(&tmp, path).map_err(|source| PipelineError::Io {
        path: path.to_owned(),
        source,
    })
}
