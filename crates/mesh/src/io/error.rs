use std::path::PathBuf;

/// Errors of mesh reading and writing. Each names the file and, for malformed content, the line
/// (text formats) or the element and its index (binary PLY).
#[derive(Debug, thiserror::Error)]
pub enum MeshIoError {
    /// The file could not be opened, read or written.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A malformed line of an OBJ file, a PLY header or an ASCII PLY body (lines count from 1).
    #[error("{}:{line}: {reason}", path.display())]
    Syntax {
        path: PathBuf,
        line: usize,
        reason: String,
    },
    /// A malformed element of a PLY body (elements count from 0 within their kind).
    #[error("{}: {element} {index}: {reason}", path.display())]
    Element {
        path: PathBuf,
        element: String,
        index: usize,
        reason: String,
    },
    /// A binary PLY body ends before all announced elements were read.
    #[error("{}: truncated: the file ends inside {element} {index} of {count}", path.display())]
    Truncated {
        path: PathBuf,
        element: String,
        index: usize,
        count: usize,
    },
    /// A file that is not a mesh format visage reads (by its name).
    #[error("{}: {reason}", path.display())]
    Format { path: PathBuf, reason: String },
    /// The mesh cannot be written in this format.
    #[error("{}: cannot write: {reason}", path.display())]
    Unwritable { path: PathBuf, reason: String },
}
