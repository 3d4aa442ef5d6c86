/// Errors of meshing.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The sample spacing must be at least one pixel.
    #[error("mesh spacing must be at least 1 pixel, got {spacing}")]
    InvalidSpacing { spacing: u32 },
    /// An image must be at least 2×2 pixels to carry a mesh.
    #[error("image of {width}×{height} pixels is too small to mesh (need at least 2×2)")]
    ImageTooSmall { width: u32, height: u32 },
    /// No grid cell is covered well enough by valid depth.
    #[error("no region with valid depth to mesh ({valid} valid pixels of {total})")]
    EmptyDomain { valid: usize, total: usize },
    /// The constrained Delaunay triangulation rejected the input.
    #[error("triangulation failed: {reason}")]
    Triangulation { reason: String },
    /// A per-vertex array has the wrong length.
    #[error("{what}: expected {expected} entries, got {got}")]
    LengthMismatch {
        what: &'static str,
        expected: usize,
        got: usize,
    },
}
