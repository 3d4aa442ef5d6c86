//! Errors of the benchmark.

use std::path::PathBuf;

/// What can go wrong in a benchmark run. Each variant carries the offending value or file.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    #[error(transparent)]
    Morphable(#[from] visage_morphable::MorphableError),
    #[error(transparent)]
    Camera(#[from] visage_camera::CameraError),
    #[error("rendering: {0}")]
    Render(#[from] visage_render::RenderError),
    #[error("fusion: {0}")]
    Fusion(#[from] visage_fusion::FusionError),
    #[error("solver: {0}")]
    Fem(#[from] visage_fem::FemError),
    /// A configuration value outside its documented range.
    #[error("invalid {name} = {value}: {reason}")]
    InvalidConfig {
        name: &'static str,
        value: String,
        reason: &'static str,
    },
    /// An unknown noise preset name.
    #[error("unknown noise preset {name:?} (known: {known})")]
    UnknownNoise { name: String, known: String },
    /// A synthesised sequence that cannot be evaluated (face out of view, nothing to mesh).
    #[error("sequence with seed {seed}: {reason}")]
    Degenerate { seed: u64, reason: String },
    /// A file could not be written.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}
