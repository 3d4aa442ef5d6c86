//! Errors of the morphable-model crate.

use std::path::PathBuf;

/// What can go wrong when importing a morphable model. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum MorphableError {
    /// A file could not be read.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A required file of the model folder is absent.
    #[error("{path}: missing ({what})")]
    MissingFile { path: PathBuf, what: &'static str },
    /// An OBJ file could not be read or is malformed (the error names the file and line).
    #[error(transparent)]
    Obj(#[from] visage_mesh::io::MeshIoError),
    /// A mode's mesh does not have the neutral mesh's vertex count.
    #[error("{path}: {got} vertices, the neutral mesh has {expected}")]
    VertexCount {
        path: PathBuf,
        expected: usize,
        got: usize,
    },
    /// `vertex_indices.json` is malformed or inconsistent with the mesh.
    #[error("{path}: {reason}")]
    Indices { path: PathBuf, reason: String },
    /// A requested expression is not part of the model folder.
    #[error("{dir}: no expression named {name:?} (available: {available})")]
    UnknownExpression {
        dir: PathBuf,
        name: String,
        available: String,
    },
    /// A computation without a unique answer.
    #[error("{what}")]
    Degenerate { what: &'static str },
    /// Weights given to [`crate::IctModel::shape`] do not match the model's modes.
    #[error("{what}: {got} weights for {expected} modes")]
    WeightCount {
        what: &'static str,
        expected: usize,
        got: usize,
    },
}
