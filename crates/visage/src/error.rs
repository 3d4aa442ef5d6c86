//! Errors of the video pipeline. Each names the input, frame or file at fault; the lower layers'
//! errors are kept as sources.

use std::path::PathBuf;

use visage_camera::CameraError;
use visage_face::FaceError;
use visage_fem::FemError;
use visage_fusion::FusionError;
use visage_run_folder::file_names;
use visage_video::VideoError;

/// What can stop a reconstruction.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An option outside its documented range (`name` as the command line spells it).
    #[error("{name} {value}: {reason}")]
    InvalidOption {
        name: &'static str,
        value: String,
        reason: &'static str,
    },
    #[error(transparent)]
    Video(#[from] VideoError),
    #[error(transparent)]
    Face(#[from] FaceError),
    #[error(transparent)]
    Camera(#[from] CameraError),
    #[error(transparent)]
    Fusion(#[from] FusionError),
    #[error(transparent)]
    Solver(#[from] FemError),
    #[error(transparent)]
    Model(#[from] visage_morphable::MorphableError),
    /// An output folder's file could not be written, read or continued.
    #[error(transparent)]
    RunFolder(#[from] visage_run_folder::RunFolderError),
    /// Rasterising the fitted face or model into a depth map failed.
    #[error("cannot render the face depth: {reason}")]
    Render { reason: String },
    /// A depth source failed (the cause names the file or frame).
    #[error(transparent)]
    Depth(Box<visage_depth::DepthError>),
    /// A step failed on one frame (`frame` names its source, `step` what was being done).
    #[error("{frame}: {step}")]
    Frame {
        frame: String,
        step: &'static str,
        source: Box<Error>,
    },
    /// An input holds nothing to process.
    #[error("{}: {reason}", path.display())]
    Input { path: PathBuf, reason: String },
    /// An input cannot be read at all (missing, not allowed).
    #[error("{}: cannot read the input", path.display())]
    Unreadable {
        path: PathBuf,
        source: std::io::Error,
    },
    /// What an option names cannot be used (`flag` as the command line spells it; the source
    /// says why).
    #[error("cannot use {flag}")]
    CannotUse {
        flag: &'static str,
        source: Box<Error>,
    },
    /// An intrinsics file for another image size than the input's (`width` × `height`).
    #[error(
        "{}: intrinsics are for another image size than {} ({width}×{height})",
        path.display(),
        input.display()
    )]
    IntrinsicsSize {
        path: PathBuf,
        input: PathBuf,
        width: u32,
        height: u32,
        source: CameraError,
    },
    /// No frame of the input got a mesh: neither detector found a face, or (`unfit` frames)
    /// one was found but its metric fit failed, for `reason`.
    #[error("{}", no_face_in_words(*frames, *unfit, reason.as_deref()))]
    NoFace {
        frames: usize,
        unfit: usize,
        reason: Option<String>,
    },
    /// No frame of the input shows a face, for a run over every face.
    #[error("{}: no face was found in any frame", path.display())]
    NoFaceInInput { path: PathBuf },
    /// The run was asked to stop (Ctrl-C, SIGTERM); the frames before it are complete.
    #[error("interrupted")]
    Interrupted,
    /// A run into the folder `dir` was asked to stop after `frames` frames: where its files
    /// are, and how to go on (`go_on`).
    #[error(
        "interrupted after {frames} frames: their meshes, {} and {} (status \"interrupted\") \
         are in {}; `visage export {}` makes the other files; {go_on}",
        file_names::LANDMARKS,
        file_names::METRICS,
        dir.display(),
        dir.display()
    )]
    RunInterrupted {
        frames: usize,
        dir: PathBuf,
        go_on: String,
    },
    /// A run into a folder stopped on `source` (which is [`Error::NoFace`] when no frame got
    /// a mesh); `context` says what the folder holds and how to go on.
    #[error("{context}")]
    RunStopped { context: String, source: Box<Error> },
    /// An export after the run failed.
    #[error(transparent)]
    Export(#[from] visage_export::ExportError),
    /// A stage thread panicked (a bug).
    #[error("internal error: the {0} stage panicked")]
    Panic(&'static str),
}

/// Why no frame got a mesh, in words.
fn no_face_in_words(frames: usize, unfit: usize, reason: Option<&str>) -> String {
    match (unfit, reason) {
        (0, _) | (_, None) => format!("no face was found in any of the {frames} frames"),
        (n, Some(reason)) => format!(
            "a face was found in {n} of the {frames} frames, but its metric fit failed ({reason}); \
             the camera's intrinsics (--fov-deg, --intrinsics) are the likely cause"
        ),
    }
}

impl Error {
    /// `source` as the failure of `step` on the frame `frame`.
    pub(crate) fn on_frame(frame: &str, step: &'static str, source: impl Into<Error>) -> Error {
        Error::Frame {
            frame: frame.to_owned(),
            step,
            source: Box::new(source.into()),
        }
    }

    /// Whether the error is a bug rather than bad input or environment.
    pub fn is_internal(&self) -> bool {
        match self {
            Error::Panic(_) => true,
            Error::Frame { source, .. }
            | Error::CannotUse { source, .. }
            | Error::RunStopped { source, .. } => source.is_internal(),
            _ => false,
        }
    }
}

impl From<visage_depth::DepthError> for Error {
    fn from(e: visage_depth::DepthError) -> Self {
        Error::Depth(Box::new(e))
    }
}
