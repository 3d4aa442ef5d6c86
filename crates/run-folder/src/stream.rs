//! What the streamed files (the blendshape curves) share: written under `<name>.tmp` frame by
//! frame, continued by a resumed run, renamed to their name when finished.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::atomic_write::tmp_path;
use crate::RunFolderError as Error;

/// Creates `tmp` (a sibling of the final file) for writing.
pub(crate) fn create_tmp(path: &Path) -> Result<(PathBuf, BufWriter<File>), Error> {
    let tmp = tmp_path(path);
    let file = File::create(&tmp).map_err(|source| Error::Write {
        path: tmp.clone(),
        source,
    })?;
    Ok((tmp, BufWriter::new(file)))
}

/// Opens `path`'s existing temporary sibling for appending.
pub(crate) fn open_tmp_for_append(path: &Path) -> Result<(PathBuf, BufWriter<File>), Error> {
    let tmp = tmp_path(path);
    let file = std::fs::OpenOptions::new()
        .append(true)
        .open(&tmp)
        .map_err(|source| Error::Write {
            path: tmp.clone(),
            source,
        })?;
    Ok((tmp, BufWriter::new(file)))
}

/// Writes `tail`, flushes `out` to `tmp` and renames it to `path`; on failure `tmp` stays
/// (with what it holds).
pub(crate) fn finish_tmp(
    mut out: BufWriter<File>,
    tail: &[u8],
    tmp: &Path,
    path: &Path,
) -> Result<PathBuf, Error> {
    let result = out
        .write_all(tail)
        .and_then(|()| out.into_inner().map_err(|e| e.into_error()))
        .map_err(|source| Error::Write {
            path: tmp.to_owned(),
            source,
        })
        .and_then(|file| {
            drop(file);
            std::fs::rename(tmp, path).map_err(|source| Error::Write {
                path: path.to_owned(),
                source,
            })
        });
    result.map(|()| path.to_owned())
}

pub(crate) fn invalid_frame(path: &Path, reason: String) -> Error {
    Error::Write {
        path: path.to_owned(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, reason),
    }
}

/// Why `fps` cannot be a timecode rate.
pub(crate) fn check_fps(fps: f64) -> Result<(), Error> {
    if fps.is_finite() && fps > 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidOption {
            name: "fps",
            value: fps.to_string(),
            reason: "must be a positive number of frames per second",
        })
    }
}
