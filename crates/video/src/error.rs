use std::path::PathBuf;

/// Errors of the frame sources. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum VideoError {
    /// A file or folder could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// An image file could not be decoded.
    #[error("{}: cannot decode the image: {reason}", path.display())]
    Image { path: PathBuf, reason: String },
    /// `ffmpeg`/`ffprobe` are not installed.
    #[error("{}: decoding video needs the FFmpeg command-line tools ({tool} not found: {reason}); install them, e.g. `apt-get install ffmpeg`", path.display())]
    ToolMissing {
        path: PathBuf,
        tool: &'static str,
        reason: String,
    },
    /// `ffprobe` found no decodable video stream.
    #[error("{}: not a readable video: {reason}", path.display())]
    NotVideo { path: PathBuf, reason: String },
    /// Decoding stopped before the end of the stream: frames before `frame` were delivered.
    #[error("{}: video is truncated or corrupt; decoding broke at frame {frame}: {reason}", path.display())]
    Broken {
        path: PathBuf,
        frame: usize,
        reason: String,
    },
    /// Encoding a video failed (`ffmpeg` refused the settings, exited with an error, or the
    /// file could not be put in place); `reason` carries ffmpeg's own message where it gave one.
    #[error("{}: cannot encode video: {reason}", path.display())]
    Encode { path: PathBuf, reason: String },
    /// An image of a folder (or list) is not the size of the first: a folder's images are the
    /// frames of one camera.
    #[error(
        "{}: this image is {}×{} but the first one, {}, is {}×{}; a folder's images are the frames of one camera and must be one size (put images of another size in a folder of their own)",
        path.display(), size.0, size.1, first.display(), first_size.0, first_size.1
    )]
    SizeChanged {
        path: PathBuf,
        size: (u32, u32),
        first: PathBuf,
        first_size: (u32, u32),
    },
    /// A folder holds no image files.
    #[error("{}: no images (.png, .jpg, .jpeg) in this folder", path.display())]
    EmptyFolder { path: PathBuf },
}
