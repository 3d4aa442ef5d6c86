use std::path::PathBuf;

/// Errors of the face front end. Every variant names the offending file or value.
#[derive(Debug, thiserror::Error)]
pub enum FaceError {
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A model file is absent from the model directory.
    #[error("model file {} is missing; run `visage models fetch` (or set VISAGE_MODELS to a directory that holds it)", path.display())]
    ModelMissing { path: PathBuf },
    /// A model file's SHA-256 differs from the pinned one (corrupt, truncated or another version).
    #[error("model file {} is corrupt or of another version: sha256 {found}, expected {expected}; run `visage models fetch --force`", path.display())]
    ModelChecksum {
        path: PathBuf,
        expected: &'static str,
        found: String,
    },
    /// A TFLite flatbuffer is malformed, uses something the engine (`visage-nn`) does not
    /// implement, or is not the network expected (input shape, output names).
    #[error("{name}: invalid or unsupported TFLite model: {reason}")]
    Tflite { name: String, reason: String },
    /// Fetching the npm package failed.
    #[error("model fetch failed: {reason}")]
    Fetch { reason: String },
    /// The canonical face-geometry metadata is malformed.
    #[error("{name}: invalid face-geometry metadata: {reason}")]
    Geometry { name: String, reason: String },
    /// An input tensor or image has the wrong size.
    #[error("input {what} has {found} values, expected {expected}")]
    InputSize {
        what: &'static str,
        expected: usize,
        found: usize,
    },
    /// An image is too small or otherwise unusable.
    #[error("invalid image: {reason}")]
    Image { reason: String },
    /// The metric face fit has no valid answer for these landmarks and this camera.
    #[error("{reason}")]
    Fit { reason: String },
    /// An option is outside its valid range.
    #[error("invalid option {name} = {value}: {reason}")]
    InvalidOption {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
}

impl From<visage_nn::NnError> for FaceError {
    fn from(e: visage_nn::NnError) -> Self {
        match e {
            visage_nn::NnError::Tflite { name, reason } => FaceError::Tflite { name, reason },
        }
    }
}
