/// Errors of the finite-element assembly and the solvers.
#[derive(Debug, thiserror::Error)]
pub enum FemError {
    /// A triangle of the planar mesh has (numerically) zero area.
    #[error("triangle {index} is degenerate (area {area:e})")]
    DegenerateTriangle { index: usize, area: f64 },
    /// A vertex has no area around it (not used by any triangle).
    #[error("vertex {index} belongs to no triangle")]
    IsolatedVertex { index: usize },
    /// λ or μ is negative, not finite or larger than [`crate::MAX_WEIGHT`].
    #[error(
        "invalid weight {name} = {}: must lie between 0 and 1e6 (larger leaves the data term no \
         weight in double precision)",
        visage_camera::number(*.value)
    )]
    InvalidWeight { name: &'static str, value: f64 },
    /// The system matrix is not numerically positive definite.
    #[error("the system matrix is not positive definite ({reason})")]
    NotPositiveDefinite { reason: String },
    /// Building a sparse matrix failed.
    #[error("sparse matrix assembly failed: {reason}")]
    Assembly { reason: String },
    /// Arrays of the wrong size were passed.
    #[error("{what}: expected {expected}, got {got}")]
    Dimension {
        what: &'static str,
        expected: usize,
        got: usize,
    },
}
