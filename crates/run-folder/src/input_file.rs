//! Which file a run read, by content: its absolute path, size and SHA-256 (`metrics.json`'s
//! `input_file`). A resumed run must read the same bytes, however the path is typed, and
//! `visage export` finds the input from any working folder.

use std::io::Read;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use crate::RunFolderError as Error;

/// An input file: where it is and what it holds.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct InputFile {
    /// The absolute path, links resolved.
    pub path: PathBuf,
    /// The size in bytes.
    pub bytes: u64,
    /// The SHA-256 digest, 64 lowercase hex digits.
    pub sha256: String,
}

impl InputFile {
    /// `path` read through once, or `None` when it is not a regular file (a folder of images,
    /// a stream).
    ///
    /// # Errors
    /// A file that cannot be read.
    pub fn of(path: &Path) -> Result<Option<InputFile>, Error> {
        if !path.is_file() {
            return Ok(None);
        }
        let (bytes, sha256) = sha256_of(path)?;
        let absolute = std::fs::canonicalize(path).map_err(|source| Error::Read {
            path: path.to_owned(),
            source,
        })?;
        Ok(Some(InputFile {
            path: absolute,
            bytes,
            sha256,
        }))
    }
}

/// The size and SHA-256 (lowercase hex) of the file at `path`, read through once.
///
/// # Errors
/// A file that cannot be read.
pub fn sha256_of(path: &Path) -> Result<(u64, String), Error> {
    let cannot_read = |source| Error::Read {
        path: path.to_owned(),
        source,
    };
    let mut file = std::fs::File::open(path).map_err(cannot_read)?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 20];
    let mut bytes = 0u64;
    loop {
        let n = file.read(&mut buf).map_err(cannot_read)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
        bytes += n as u64;
    }
    let sha256 = hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    Ok((bytes, sha256))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_is_known_by_its_content_and_absolute_path() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("clip.mp4");
        std::fs::write(&path, b"abc").unwrap();
        let f = InputFile::of(&path).unwrap().unwrap();
        assert_eq!(f.bytes, 3);
        assert_eq!(
            f.sha256,
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        assert!(f.path.is_absolute());
        assert_eq!(InputFile::of(dir.path()).unwrap(), None, "a folder");
    }
}
