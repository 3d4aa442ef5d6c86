use std::path::{Path, PathBuf};

use crate::ffmpeg::VideoReader;
use crate::{Frame, FramePool, VideoError};

/// File extensions read as still images (case-insensitive).
pub const IMAGE_EXTENSIONS: [&str; 3] = ["png", "jpg", "jpeg"];

/// Whether `path` names a still image by its extension.
pub fn is_image_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| IMAGE_EXTENSIONS.iter().any(|x| x.eq_ignore_ascii_case(e)))
}

/// Whether a file's name starts with a dot (hidden on Unix; macOS writes `._name` beside
/// files copied to foreign disks).
fn is_hidden(path: &Path) -> bool {
    path.file_name()
        .is_some_and(|n| n.to_string_lossy().starts_with('.'))
}

/// Reads one image file as RGB8, turned upright as its EXIF orientation says (a phone's
/// portrait photo is stored sideways with a tag that says so; video rotation metadata is
/// honoured the same way by the video reader).
pub fn read_image(path: &Path) -> Result<Frame, VideoError> {
    let bytes = std::fs::read(path).map_err(|source| VideoError::Io {
        path: path.to_owned(),
        source,
    })?;
    decode_image(&bytes, path)
}

/// [`read_image`] of a file's bytes; `path` only names it in errors and in the frame.
pub fn decode_image(bytes: &[u8], path: &Path) -> Result<Frame, VideoError> {
    use image::ImageDecoder;
    let in_words = |e: image::ImageError| VideoError::Image {
        path: path.to_owned(),
        reason: image_error_in_words(&e),
    };
    let mut decoder = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| in_words(image::ImageError::IoError(e)))?
        .into_decoder()
        .map_err(in_words)?;
    // An unreadable orientation tag is no orientation: the pixels as stored.
    let orientation = decoder
        .orientation()
        .unwrap_or(image::metadata::Orientation::NoTransforms);
    let mut img = image::DynamicImage::from_decoder(decoder).map_err(in_words)?;
    img.apply_orientation(orientation);
    Ok(Frame {
        index: 0,
        source: path.display().to_string(),
        timestamp_s: None,
        image: img.to_rgb8(),
    })
}

/// What went wrong with an image file, in words (the decoders' own texts quote their internal
/// error names).
fn image_error_in_words(e: &image::ImageError) -> String {
    use image::error::ImageFormatHint;
    use image::ImageError;
    let format = |hint: &ImageFormatHint| match hint {
        ImageFormatHint::Exact(f) => f
            .extensions_str()
            .first()
            .map_or_else(|| "image".to_owned(), |x| x.to_uppercase()),
        _ => "image".to_owned(),
    };
    match e {
        ImageError::Decoding(d) => {
            format!(
                "the {} data is damaged or truncated",
                format(&d.format_hint())
            )
        }
        ImageError::Unsupported(_) => {
            "not an image format visage reads (PNG or JPEG), or a variant of one it does not"
                .to_owned()
        }
        ImageError::Limits(_) => "the image is larger than the decoder's memory limit".to_owned(),
        ImageError::IoError(io) => format!("read error: {io}"),
        other => other.to_string(),
    }
}

/// A stream of frames from a video file, a folder of images (name order) or one image.
pub enum FrameSource {
    /// A video decoded by FFmpeg.
    Video(VideoReader),
    /// Image files, read one at a time; `fps` is the frame rate the caller gave
    /// ([`FrameSource::with_frame_rate`]), which the files themselves do not state, and
    /// `times` each file's capture time in seconds when a recording lists them
    /// ([`FrameSource::timed_images`]).
    Images {
        paths: Vec<PathBuf>,
        next: usize,
        fps: Option<f64>,
        times: Option<Vec<f64>>,
        /// The first image read and its size, which every other must have.
        first: Option<(PathBuf, (u32, u32))>,
    },
    /// Frames made by the caller as they are asked for (a renderer, a capture callback), of
    /// `width × height` pixels, `count` of them when known, at `fps` when known
    /// ([`FrameSource::generated`]).
    Generated {
        frames: Box<dyn Iterator<Item = Result<Frame, VideoError>> + Send>,
        width: u32,
        height: u32,
        count: Option<usize>,
        fps: Option<f64>,
    },
}

impl FrameSource {
    /// Where a video's frame buffers come from, to hand frames back to once they are done
    /// with ([`FramePool`]); `None` for images and generated frames.
    pub fn frame_pool(&self) -> Option<FramePool> {
        match self {
            FrameSource::Video(reader) => Some(reader.frame_pool()),
            _ => None,
        }
    }

    /// Opens `path`: a folder → its `.png/.jpg/.jpeg` files sorted by name (hidden files left
    /// out: macOS's `._name.jpg` resource forks and other dot-files are not frames); an image
    /// file → that image; anything else → a video through FFmpeg.
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
                .filter(|p| is_image_path(p) && !is_hidden(p))
                .collect();
            if paths.is_empty() {
                return Err(VideoError::EmptyFolder {
                    path: path.to_owned(),
                });
            }
            paths.sort();
            return Ok(FrameSource::Images {
                paths,
                next: 0,
                fps: None,
                times: None,
                first: None,
            });
        }
        if is_image_path(path) {
            return Ok(FrameSource::Images {
                paths: vec![path.to_owned()],
                next: 0,
                fps: None,
                times: None,
                first: None,
            });
        }
        Ok(FrameSource::Video(VideoReader::open(path)?))
    }

    /// Image files in the given order with their capture times (seconds, one per file, e.g.
    /// an RGB-D recording's list): image `i`'s timestamp is `times[i] − times[0]`. `fps` is the
    /// recording's nominal rate, if known.
    ///
    /// # Errors
    /// No files, or not one time per file.
    pub fn timed_images(
        paths: Vec<PathBuf>,
        times: Vec<f64>,
        fps: Option<f64>,
    ) -> Result<FrameSource, VideoError> {
        let Some(first) = paths.first() else {
            return Err(VideoError::EmptyFolder {
                path: PathBuf::new(),
            });
        };
        if times.len() != paths.len() {
            return Err(VideoError::Image {
                path: first.clone(),
                reason: format!("{} images but {} timestamps", paths.len(), times.len()),
            });
        }
        Ok(FrameSource::Images {
            paths,
            next: 0,
            fps: fps.filter(|f| f.is_finite() && *f > 0.0),
            times: Some(times),
            first: None,
        })
    }

    /// Frames from `frames`, each `width × height` pixels, made one at a time as the source is
    /// read (on the reading thread); `count` is how many there will be and `fps` their rate,
    /// when known. The frames keep the index and timestamp they are made with.
    pub fn generated(
        width: u32,
        height: u32,
        count: Option<usize>,
        fps: Option<f64>,
        frames: impl Iterator<Item = Result<Frame, VideoError>> + Send + 'static,
    ) -> FrameSource {
        FrameSource::Generated {
            frames: Box::new(frames),
            width,
            height,
            count,
            fps: fps.filter(|f| f.is_finite() && *f > 0.0),
        }
    }

    /// Gives images the frame rate they were taken at: image `i` is then at `i / fps`
    /// seconds ([`Frame::timestamp_s`]). Without it images have no timestamps. A video keeps
    /// its own timestamps and ignores this; an `fps` that is not positive and finite is ignored.
    pub fn with_frame_rate(mut self, fps: f64) -> FrameSource {
        if let FrameSource::Images { fps: rate, .. } = &mut self {
            if fps.is_finite() && fps > 0.0 {
                *rate = Some(fps);
            }
        }
        self
    }

    /// The frame rate: a video's stream rate ([`VideoInfo::fps`](crate::VideoInfo::fps)), the
    /// rate given to images, `None` when unknown.
    pub fn frame_rate(&self) -> Option<f64> {
        match self {
            FrameSource::Video(v) => v.info().fps,
            FrameSource::Images { fps, .. } | FrameSource::Generated { fps, .. } => *fps,
        }
    }
}

impl Iterator for FrameSource {
    type Item = Result<Frame, VideoError>;

    fn next(&mut self) -> Option<Self::Item> {
        match self {
            FrameSource::Video(v) => v.next(),
            FrameSource::Generated { frames, .. } => frames.next(),
            FrameSource::Images {
                paths,
                next,
                fps,
                times,
                first,
            } => {
                let path = paths.get(*next)?;
                let index = *next;
                *next += 1;
                let timestamp_s = match times {
                    Some(t) => Some(t[index] - t[0]),
                    None => fps.map(|f| index as f64 / f),
                };
                let frame = match read_image(path) {
                    Ok(f) => f,
                    Err(e) => return Some(Err(e)),
                };
                let size = frame.image.dimensions();
                match first {
                    None => *first = Some((path.clone(), size)),
                    Some((first_path, first_size)) if *first_size != size => {
                        return Some(Err(VideoError::SizeChanged {
                            path: path.clone(),
                            size,
                            first: first_path.clone(),
                            first_size: *first_size,
                        }))
                    }
                    Some(_) => {}
                }
                Some(Ok(Frame {
                    index,
                    timestamp_s,
                    ..frame
                }))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A JPEG of `w`×`h` whose left half is white, with an EXIF orientation tag when given.
    fn jpeg(w: u32, h: u32, orientation: Option<u16>) -> Vec<u8> {
        let img = image::RgbImage::from_fn(w, h, |x, _| {
            if x < w / 2 {
                image::Rgb([255, 255, 255])
            } else {
                image::Rgb([0, 0, 0])
            }
        });
        let mut bytes = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 95)
            .encode_image(&img)
            .unwrap();
        match orientation {
            Some(o) => visage_testdata::with_exif_orientation(&bytes, o),
            None => bytes,
        }
    }

    #[test]
    fn a_folder_leaves_hidden_files_out() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a.jpg"), jpeg(8, 8, None)).unwrap();
        std::fs::write(dir.path().join("._a.jpg"), b"\0\x05\x16\x07 AppleDouble").unwrap();
        match FrameSource::open(dir.path()).unwrap() {
            FrameSource::Images { paths, .. } => {
                assert_eq!(paths, [dir.path().join("a.jpg")]);
            }
            _ => panic!("not an image folder"),
        }
    }

    #[test]
    fn a_photo_is_turned_upright_as_its_exif_orientation_says() {
        let dir = tempfile::tempdir().unwrap();
        let plain = dir.path().join("plain.jpg");
        std::fs::write(&plain, jpeg(64, 32, None)).unwrap();
        let f = read_image(&plain).unwrap();
        assert_eq!(f.image.dimensions(), (64, 32));
        // Orientation 6: stored sideways, shown turned 90° clockwise. The white left half of
        // the stored pixels becomes the top half.
        let sideways = dir.path().join("portrait.jpg");
        std::fs::write(&sideways, jpeg(64, 32, Some(6))).unwrap();
        let f = read_image(&sideways).unwrap();
        assert_eq!(f.image.dimensions(), (32, 64));
        assert!(f.image.get_pixel(16, 8)[0] > 200 && f.image.get_pixel(16, 56)[0] < 50);
    }
}
