use std::path::{Path, PathBuf};

use crate::ffmpeg::VideoReader;
use crate::{Frame, VideoError};

/// File extensions read as still images (case-insensitive).
pub const IMAGE_EXTENSIONS: [&str; 3] = ["png", "jpg", "jpeg"];

/// Whether `path` names a still image by its extension.
pub fn is_image_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| IMAGE_EXTENSIONS.iter().any(|x| x.eq_ignore_ascii_case(e)))
}

/// Reads one image file as RGB8.
pub fn read_image(path: &Path) -> Result<Frame, VideoError> {
    let bytes = std::fs::read(path).map_err(|source| VideoError::Io {
        path: path.to_owned(),
        source,
    })?;
    let img = image::load_from_memory(&bytes).map_err(|e| VideoError::Image {
        path: path.to_owned(),
        reason: e.to_string(),
    })?;
    Ok(Frame {
        index: 0,
        source: path.display().to_string(),
        image: img.to_rgb8(),
    })
}

/// A stream of frames from a video file, a folder of images (name order) or one image.
pub enum FrameSource {
    /// A video decoded by FFmpeg.
    Video(VideoReader),
    /// Image files, read one at a time.
    Images { paths: Vec<PathBuf>, next: usize },
}

impl FrameSource {
    /// Opens `path`: a folder → its `.png/.jpg/.jpeg` files sorted by name; an image file → that
    /// image; anything else → a video through FFmpeg.
    pub fn open(path: &Path) -> Result<FrameSource, VideoError> {
        let meta = std::fs::metadata(path).map_err(|source| VideoError::Io {
            path: path.to_owned(),
            source,
        })?;
        if meta.is_dir() {
            let entries = std::fs::read_dir(path).map_err(|source| VideoError::Io {
                path: path.to_owned(),
                source,
            })?;
            let mut paths: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| is_image_path(p))
                .collect();
            if paths.is_empty() {
                return Err(VideoError::EmptyFolder {
                    path: path.to_owned(),
                });
            }
            paths.sort();
            return Ok(FrameSource::Images { paths, next: 0 });
        }
        if is_image_path(path) {
            return Ok(FrameSource::Images {
                paths: vec![path.to_owned()],
                next: 0,
            });
        }
        Ok(FrameSource::Video(VideoReader::open(path)?))
    }
}

impl Iterator for FrameSource {
    type Item = Result<Frame, VideoError>;

    fn next(&mut self) -> Option<Self::Item> {
        match self {
            FrameSource::Video(v) => v.next(),
            FrameSource::Images { paths, next } => {
                let path = paths.get(*next)?;
                let index = *next;
                *next += 1;
                Some(read_image(path).map(|f| Frame { index, ..f }))
            }
        }
    }
}
