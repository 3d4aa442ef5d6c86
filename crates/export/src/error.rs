use std::path::PathBuf;

/// Errors of the exports. Each names the file at fault.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{}: cannot read: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: cannot write: {source}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: {reason}", path.display())]
    Malformed { path: PathBuf, reason: String },
    #[error("{}: does not match the run's other files: {reason}", path.display())]
    Mismatch { path: PathBuf, reason: String },
    /// A folder that is not a finished run's, and what to do instead.
    #[error("{}: {reason}", dir.display())]
    NotARun { dir: PathBuf, reason: String },
    #[error("{}: no frame has a mesh: nothing to export", path.display())]
    Empty { path: PathBuf },
    #[error(transparent)]
    Camera(#[from] visage_camera::CameraError),
    #[error(transparent)]
    Mesh(#[from] visage_mesh::io::MeshIoError),
    #[error(transparent)]
    Render(#[from] visage_render::RenderError),
    #[error(transparent)]
    Video(#[from] visage_video::VideoError),
    #[error("{0}")]
    Internal(String),
}
