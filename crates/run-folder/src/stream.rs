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

    /// A stream over `path`'s temporary sibling, already open as `out`.
    pub(crate) fn from_writer(path: &Path, out: BufWriter<File>) -> Stream {
        Stream {
            path: path.to_owned(),
            tmp: tmp_path(path),
            out,
        }
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
    pub(crate) fn finish(self, tail: &[u8]) -> Result<PathBuf, Error> {
        self.complete(tail)?.publish()
    }

    /// Writes `tail` and hands everything to the operating system, still under the temporary
    /// name: [`Completed::publish`] renames it, [`Completed::withdraw`] takes the tail off again
    /// (a run whose other files could not be finished stays resumable). When the tail cannot
    /// be written it is taken off at once and the file holds what it held before.
    pub(crate) fn complete(mut self, tail: &[u8]) -> Result<Completed, Error> {
        let body = self
            .out
            .flush()
            .and_then(|()| self.out.get_ref().metadata())
            .map(|m| m.len())
            .map_err(|source| self.io_error(source))?;
        let completed = Completed {
            path: self.path.clone(),
            tmp: self.tmp.clone(),
            body,
        };
        let written = self.out.write_all(tail).and_then(|()| self.out.flush());
        if let Err(source) = written {
            // The tail's bytes that reached the file come off; the buffer's are dropped.
            let (file, _) = self.out.into_parts();
            let _ = file.set_len(body);
            return Err(Error::Write {
                path: completed.tmp,
                source,
            });
        }
        Ok(completed)
    }

    /// A failure to write the temporary file.
    pub(crate) fn io_error(&self, source: std::io::Error) -> Error {
        Error::Write {
            path: self.tmp.clone(),
            source,
        }
    }
}

/// A streamed file written to its end under its temporary name, not yet renamed.
#[derive(Debug)]
pub(crate) struct Completed {
    path: PathBuf,
    tmp: PathBuf,
    /// The file's length before its tail.
    body: u64,
}

impl Completed {
    /// Renames the file to its final name, which it returns.
    pub(crate) fn publish(self) -> Result<PathBuf, Error> {
        std::fs::rename(&self.tmp, &self.path).map_err(|source| Error::Write {
            path: self.path.clone(),
            source,
        })?;
        Ok(self.path)
    }

    /// Takes the tail off again, leaving the temporary file as it was before
    /// [`Stream::complete`] (a shorter file always fits on the disk).
    pub(crate) fn withdraw(self) -> Result<(), Error> {
        std::fs::OpenOptions::new()
            .write(true)
            .open(&self.tmp)
            .and_then(|f| f.set_len(self.body))
            .map_err(|source| Error::Write {
                path: self.tmp,
                source,
            })
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
