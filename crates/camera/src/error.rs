use std::path::PathBuf;

/// Errors of the camera crate. Every variant names the offending value or file.
#[derive(Debug, thiserror::Error)]
pub enum CameraError {
    /// An intrinsic parameter is non-positive or not finite.
    #[error("invalid intrinsics: {field} = {} ({reason})", crate::number(*.value))]
    InvalidIntrinsics {
        field: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// A file's intrinsics are invalid (the cause says which value and why).
    #[error("{}: {source}", path.display())]
    InvalidIntrinsicsFile {
        path: PathBuf,
        source: Box<CameraError>,
    },
    /// The intrinsics describe another image size than the one given.
    #[error("intrinsics are for {expected_width}×{expected_height} images but the frame is {width}×{height}")]
    SizeMismatch {
        expected_width: u32,
        expected_height: u32,
        width: u32,
        height: u32,
    },
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// An intrinsics file is not the expected JSON.
    #[error("{}: not a valid intrinsics file: {source}", path.display())]
    Json {
        path: PathBuf,
        source: serde_json::Error,
    },
    /// A rigid transform has a non-finite entry or a rotation that is not proper
    /// ([`crate::RigidTransform::validate`]).
    #[error("degenerate rigid transform: {reason}")]
    InvalidTransform { reason: String },
    /// A rigid-transform (pose) file is unreadable, not the expected JSON or not a rigid motion.
    #[error("{}: {reason}", path.display())]
    TransformFile { path: PathBuf, reason: String },
    /// A depth image is unreadable or of the wrong kind.
    #[error("{}: {reason}", path.display())]
    DepthImage { path: PathBuf, reason: String },
}
