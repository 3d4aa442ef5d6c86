use std::path::PathBuf;

/// Errors of the depth sources. Every variant names the file (or option) at fault.
#[derive(Debug, thiserror::Error)]
pub enum DepthError {
    /// A file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A network's description file (its JSON) is not valid.
    #[error("{}: not a valid depth network description: {reason}", path.display())]
    Config { path: PathBuf, reason: String },
    /// The file is not an ONNX model the runtime can read.
    #[error("{}: not an ONNX model: {reason}", path.display())]
    NotOnnx { path: PathBuf, reason: String },
    /// The network uses operators the ONNX runtime does not implement.
    #[error(
        "{}: the network uses operators visage's ONNX runtime (tract) does not implement: {}",
        path.display(), ops.join(", ")
    )]
    UnsupportedOperators { path: PathBuf, ops: Vec<String> },
    /// The network's input or output is not what a depth network has.
    #[error("{}: {reason}", path.display())]
    Shape { path: PathBuf, reason: String },
    /// The runtime failed to prepare or run the network.
    #[error("{}: {reason}", path.display())]
    Runtime { path: PathBuf, reason: String },
    /// A depth folder holds no PNG.
    #[error("{}: no PNG depth frames found", dir.display())]
    NoFrames { dir: PathBuf },
    /// A depth folder has fewer frames than the input.
    #[error("{}: holds {frames} depth frames; input frame {index} has none", dir.display())]
    MissingFrame {
        dir: PathBuf,
        frames: usize,
        index: usize,
    },
    /// Depth units per metre that are not a positive finite number.
    #[error("invalid option depth-scale = {value}: must be positive and finite")]
    DepthScale { value: f64 },
    /// An RGB-D recording's folder or lists are not usable.
    #[error("{}: {reason}", path.display())]
    Recording { path: PathBuf, reason: String },
    /// A camera file or depth image failed (the cause names the file).
    #[error(transparent)]
    Camera(#[from] visage_camera::CameraError),
    /// A step failed on one frame (`frame` names the frame or its file, `step` what was being
    /// done).
    #[error("{frame}: {step}")]
    Frame {
        frame: String,
        step: &'static str,
        source: Box<DepthError>,
    },
    /// An option outside its range.
    #[error("{name} = {value}: {reason}")]
    InvalidOption {
        name: &'static str,
        value: String,
        reason: &'static str,
    },
}

impl DepthError {
    /// `source` as the failure of `step` on the frame `frame` (a name for the user: the input
    /// frame's source, or the depth file read for it).
    pub fn on_frame(frame: &str, step: &'static str, source: impl Into<DepthError>) -> DepthError {
        DepthError::Frame {
            frame: frame.to_owned(),
            step,
            source: Box::new(source.into()),
        }
    }
}
