//! Errors of the benchmark.

use std::path::PathBuf;

/// What can go wrong in a benchmark run. Each variant carries the offending value or file.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    #[error(transparent)]
    Morphable(#[from] visage_morphable::MorphableError),
    #[error(transparent)]
    Camera(#[from] visage_camera::CameraError),
    #[error(transparent)]
    Mesh(#[from] visage_mesh::io::MeshIoError),
    #[error("rendering: {0}")]
    Render(#[from] visage_render::RenderError),
    #[error("fusion: {0}")]
    Fusion(#[from] visage_fusion::FusionError),
    #[error("solver: {0}")]
    Fem(#[from] visage_fem::FemError),
    #[error("face networks: {0}")]
    Face(#[from] visage_face::FaceError),
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
    /// A clip could not be opened or the pipeline not set up for it. The message is the
    /// pipeline's own, and the pipeline's error stays in the chain as the source (not
    /// `transparent`), so the binary still tells an internal error from bad input.
    #[error("{0}")]
    Pipeline(#[from] visage::Error),
    /// One of a clip's runs stopped with an error (boxed: the pipeline's error is large).
    #[error(transparent)]
    ClipRun(Box<ClipRunError>),
    /// A run of a clip tracked other landmarks than the `reference` run; the runs must differ
    /// only after tracking.
    #[error(
        "{}: the {run} run tracked other landmarks than the {reference} run",
        clip.display()
    )]
    TrackingDiffers {
        clip: PathBuf,
        run: &'static str,
        reference: &'static str,
    },
    /// No run of a clip has three consecutive frames with a face to measure.
    #[error("{}: no three consecutive frames with a face", clip.display())]
    NoSegments { clip: PathBuf },
    /// A folder could not be created.
    #[error("{}: cannot create", path.display())]
    CreateDir {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// An image could not be written (the renderer's error names the file).
    #[error(transparent)]
    WriteImage(visage_render::RenderError),
    /// A file could not be written.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// One of a clip's runs (`run`: "per-frame fit", "streaming", "causal" or "clip") stopped with
/// the pipeline's error `source`.
#[derive(Debug, thiserror::Error)]
#[error("{}: the {run} run failed", clip.display())]
pub struct ClipRunError {
    pub clip: PathBuf,
    pub run: &'static str,
    #[source]
    pub source: visage::Error,
}
