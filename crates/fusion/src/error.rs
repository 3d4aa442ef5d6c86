use std::path::PathBuf;

use visage_camera::CameraError;
use visage_fem::FemError;
use visage_mesh::io::MeshIoError;
use visage_mesh::MeshError;

/// Errors of the fusion. Each names the file or parameter at fault.
#[derive(Debug, thiserror::Error)]
pub enum FusionError {
    #[error(transparent)]
    Camera(#[from] CameraError),
    #[error("meshing: {0}")]
    Mesh(#[from] MeshError),
    #[error("solver: {0}")]
    Fem(#[from] FemError),
    #[error(transparent)]
    MeshIo(#[from] MeshIoError),
    #[error("{}: frame is {width}×{height} but the first frame is {expected_width}×{expected_height}", path.display())]
    FrameSize {
        path: PathBuf,
        width: u32,
        height: u32,
        expected_width: u32,
        expected_height: u32,
    },
    #[error("{}: no frame has any valid depth", dir.display())]
    NoValidDepth { dir: PathBuf },
    /// A frame lacks an input its design needs.
    #[error("{what}")]
    MissingInput { what: &'static str },
    /// The image-plane mesh at this spacing would have more vertices than [`MAX_MESH_VERTICES`]
    /// (memory grows with them, the factorisation faster still).
    ///
    /// [`MAX_MESH_VERTICES`]: crate::MAX_MESH_VERTICES
    #[error(
        "--spacing {spacing}: the mesh over this face's {pixels} pixels would have about {estimate} vertices, more than the {limit} visage meshes; use --spacing {smallest} or more"
    )]
    TooManyVertices {
        spacing: u32,
        pixels: usize,
        estimate: usize,
        limit: usize,
        smallest: u32,
    },
    #[error("invalid option {name} = {value}: {reason}")]
    InvalidOption {
        name: &'static str,
        value: String,
        reason: &'static str,
    },
}
