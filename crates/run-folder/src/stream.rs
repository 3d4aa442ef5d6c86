//! What the streamed files (the blendshape curves) share: written under `<name>.tmp` frame by
//! frame, continued by a resumed run, renamed to their name when finished.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use visage_rig::BlendshapeFrame;

use crate::atomic_write::tmp_path;
use crate::RunFolderError as Error;

/// A file streamed under `<name>.tmp`: started or continued, written piece by piece, handed to
/// the operating system on request, renamed to its name when finished. Dropped unfinished (or
/// when finishing fails), what was written stays under the temporary name, where
/// `visage run --resume` finds it.
pub(crate) struct Stream {
    path: PathBuf,
    tmp: PathBuf,
    out: BufWriter<File>,
}

impl Stream {
    /// Starts `path`'s temporary sibling, empty.
    pub(crate) fn create(path: &Path) -> Result<Stream, Error> {
        let tmp = tmp_path(path);
        let file = File::create(&tmp).map_err(|source| Error::Write {
            path: tmp.clone(),
            source,
        })?;
        Ok(Stream::new(path, tmp, file))
    }

    /// Continues `path`'s existing temporary sibling.
    pub(crate) fn append(path: &Path) -> Result<Stream, Error> {
        let tmp = tmp_path(path);
        let file = std::fs::OpenOptions::new()
            .append(true)
            .open(&tmp)
            .map_err(|source| Error::Write {
                path: tmp.clone(),
                source,
            })?;
        Ok(Stream::new(path, tmp, file))
    }

    fn new(path: &Path, tmp: PathBuf, file: File) -> Stream {
        Stream {
            path: path.to_owned(),
            tmp,
            out: BufWriter::new(file),
        }
    }

    /// The final path.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// Appends `bytes`.
    pub(crate) fn write(&mut self, bytes: &[u8]) -> Result<(), Error> {
        let result = self.out.write_all(bytes);
        result.map_err(|source| self.io_error(source))
    }

    /// Hands what was written to the operating system.
    pub(crate) fn flush(&mut self) -> Result<(), Error> {
        let result = self.out.flush();
        result.map_err(|source| self.io_error(source))
    }

    /// Why `frame` cannot be written (a non-finite or negative time, a non-finite value), as
    /// an error naming the file.
    pub(crate) fn check(&self, frame: &BlendshapeFrame) -> Result<(), Error> {
        frame.check().map_err(|reason| Error::Write {
            path: self.path.clone(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidInput, reason),
        })
    }

    /// Writes `tail`, flushes, and renames the file to its final name, which it returns; on
    /// failure the temporary file stays (with what it holds).
    pub(crate) fn finish(mut self, tail: &[u8]) -> Result<PathBuf, Error> {
        let (tmp, path) = (self.tmp, self.path);
        let result = self
            .out
            .write_all(tail)
            .and_then(|()| self.out.into_inner().map_err(|e| e.into_error()))
            .map_err(|source| Error::Write {
                path: tmp.clone(),
                source,
            })
            .and_then(|file| {
                drop(file);
                std::fs::rename(&tmp, &path).map_err(|source| Error::Write {
                    path: path.clone(),
                    source,
                })
            });
        result.map(|()| path)
    }

    /// A failure to write the temporary file.
    pub(crate) fn io_error(&self, source: std::io::Error) -> Error {
        Error::Write {
            path: self.tmp.clone(),
            source,
        }
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
