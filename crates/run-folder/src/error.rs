//! Errors of an output folder's files. Each names the file or folder at fault.

use std::path::PathBuf;

use visage_mesh::io::MeshIoError;

/// What can go wrong writing, reading or continuing a run's files.
#[derive(Debug, thiserror::Error)]
pub enum RunFolderError {
    /// An option outside its documented range (`name` as the command line spells it).
    #[error("{name} {value}: {reason}")]
    InvalidOption {
        name: &'static str,
        value: String,
        reason: &'static str,
    },
    /// A file holds nothing usable.
    #[error("{}: {reason}", path.display())]
    Input { path: PathBuf, reason: String },
    /// An output file or folder could not be written.
    #[error("cannot write {}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A file of a previous run could not be read.
    #[error("cannot read {}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A previous run in an output folder cannot be continued (`reason` says why and what to
    /// do instead).
    #[error("{}: cannot resume the run in this folder: {reason}", dir.display())]
    Resume { dir: PathBuf, reason: String },
    /// An output folder that holds something else than a run to continue.
    #[error(
        "{}: the output folder is not empty; it holds {holds}. Pass --overwrite to replace a \
         previous run's files (other files stay), or choose another folder",
        dir.display()
    )]
    NotEmpty { dir: PathBuf, holds: String },
    /// `--overwrite` of a folder that no visage run wrote to.
    #[error(
        "{}: --overwrite replaces a previous visage run, and this folder does not hold one; it \
         holds {holds}. Nothing was removed: choose another folder, or remove these yourself",
        dir.display()
    )]
    NotARun { dir: PathBuf, holds: String },
    /// Another process writes into the output folder.
    #[error(
        "{}: the output folder is in use by another visage process ({holder}); wait for it to \
         finish or stop it, or choose another folder",
        dir.display()
    )]
    Locked { dir: PathBuf, holder: String },
    /// A mesh or point cache could not be read (the mesh reader's error, which names the file).
    #[error(transparent)]
    ReadMesh(#[from] MeshIoError),
    /// A frame of something else than a point cache was asked for.
    #[error("--frame needs a point cache (OUT/sequence.pc2), not {}", path.display())]
    FrameWithoutCache { path: PathBuf },
    /// A point cache was given without the frame to take from it.
    #[error("{}: a point cache needs --frame N (the sample to render)", path.display())]
    CacheWithoutFrame { path: PathBuf },
    /// A point cache whose points a frame are not the vertices of the mesh beside it.
    #[error(
        "{}: {points} points a frame, {} has {vertices} vertices",
        cache.display(),
        mesh.display()
    )]
    CacheMeshMismatch {
        cache: PathBuf,
        points: usize,
        mesh: PathBuf,
        vertices: usize,
    },
    /// A frame past the point cache's last sample.
    #[error("{}: --frame {frame}: the cache has {samples} samples", cache.display())]
    CacheFrameOutOfRange {
        cache: PathBuf,
        frame: usize,
        samples: usize,
    },
    /// A mesh file could not be written.
    #[error("cannot write {}", path.display())]
    WriteMesh { path: PathBuf, source: MeshIoError },
}
