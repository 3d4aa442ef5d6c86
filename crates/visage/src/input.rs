//! A reconstruction's input: a video file (decoded by FFmpeg), a folder of images (name
//! order) or one image, with the frame size, the frame count when known, and which frames to
//! keep.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use visage_run_folder::FrameSelection;
use visage_video::{
    focal_length_35mm, is_image_path, read_image, Frame, FramePool, FrameSource, VideoError,
};

use crate::Error;

/// Frames from a video, an image folder or an image, in input order.
pub struct Input {
    path: PathBuf,
    source: FrameSource,
    width: u32,
    height: u32,
    frame_count: Option<usize>,
    every: usize,
    max_frames: Option<usize>,
    /// Frames up to this input index were processed by an earlier run (`--resume`): skipped.
    after: Option<usize>,
    kept: usize,
    /// Which kept frames to copy, and where to.
    copies: Option<(FrameFilter, KeptFrames)>,
    /// Set from outside (Ctrl-C): the input ends before its next frame.
    stop: Option<Arc<AtomicBool>>,
    /// Where the source's frame buffers come from (a video's), to hand frames back to.
    pool: Option<FramePool>,
}

/// Chooses the frames [`Input::keep_copies`] copies.
pub type FrameFilter = Box<dyn FnMut(&Frame) -> bool + Send>;

/// Copies of some of an input's frames, taken as they are decoded (on whichever thread decodes
/// them) and kept for after the run — e.g. to colour a texture without decoding again.
#[derive(Clone, Default)]
pub struct KeptFrames(Arc<Mutex<Vec<Frame>>>);

impl KeptFrames {
    /// The frames copied so far, in input order (and forgets them).
    pub fn take(&self) -> Vec<Frame> {
        self.0
            .lock()
            .map(|mut v| std::mem::take(&mut *v))
            .unwrap_or_default()
    }
}

impl Input {
    /// Opens `path` and reads the frame size (a video's stream header, or the first image).
    ///
    /// # Errors
    /// A missing or unreadable input, a folder without images, a file FFmpeg cannot read.
    pub fn open(path: &Path) -> Result<Input, Error> {
        Input::from_source(path, FrameSource::open(path)?)
    }

    /// The colour frames of a recording (`path`, e.g. an RGB-D folder): `paths` in this order
    /// with their capture `times` in seconds (the frames' timestamps count from the first),
    /// `fps` the recording's nominal rate.
    ///
    /// # Errors
    /// No images, not one time per image, an unreadable first image.
    pub fn timed_images(
        path: &Path,
        paths: Vec<PathBuf>,
        times: Vec<f64>,
        fps: Option<f64>,
    ) -> Result<Input, Error> {
        Input::from_source(path, FrameSource::timed_images(paths, times, fps)?)
    }

    /// Frames the caller makes as they are read (on the decoding thread; e.g. renders of a
    /// synthetic face), `width × height` pixels, `count` of them when known, at `fps` when
    /// known, named `path` in records and messages ([`FrameSource::generated`]).
    pub fn generated(
        path: &Path,
        width: u32,
        height: u32,
        count: Option<usize>,
        fps: Option<f64>,
        frames: impl Iterator<Item = Result<Frame, VideoError>> + Send + 'static,
    ) -> Input {
        Input::with_size(
            path,
            FrameSource::generated(width, height, count, fps, frames),
            (width, height, count),
        )
    }

    fn from_source(path: &Path, source: FrameSource) -> Result<Input, Error> {
        let size = match &source {
            FrameSource::Generated {
                width,
                height,
                count,
                ..
            } => (*width, *height, *count),
            FrameSource::Video(reader) => {
                let info = reader.info();
                (info.width, info.height, info.frame_count)
            }
            FrameSource::Images { paths, .. } => {
                let first = paths.first().ok_or_else(|| Error::Input {
                    path: path.to_owned(),
                    reason: "no images".into(),
                })?;
                if !is_image_path(first) {
                    return Err(Error::Input {
                        path: first.clone(),
                        reason: "not an image".into(),
                    });
                }
                let (w, h) = read_image(first)?.image.dimensions();
                (w, h, Some(paths.len()))
            }
        };
        Ok(Input::with_size(path, source, size))
    }

    fn with_size(
        path: &Path,
        source: FrameSource,
        (width, height, frame_count): (u32, u32, Option<usize>),
    ) -> Input {
        Input {
            path: path.to_owned(),
            pool: source.frame_pool(),
            source,
            width,
            height,
            frame_count,
            every: 1,
            max_frames: None,
            after: None,
            kept: 0,
            copies: None,
            stop: None,
        }
    }

    /// Where the frames' buffers come from, for a video: a frame handed back to it once its
    /// stage is done with it ([`FramePool::recycle`]) lends its buffer to a later frame.
    pub fn frame_pool(&self) -> Option<FramePool> {
        self.pool.clone()
    }

    /// Keeps only the frames whose index is a multiple of `every` (they keep their index).
    ///
    /// # Errors
    /// `every` = 0.
    pub fn every(mut self, every: usize) -> Result<Input, Error> {
        if every == 0 {
            return Err(Error::InvalidOption {
                name: "--every",
                value: "0".into(),
                reason: "must be at least 1",
            });
        }
        self.every = every;
        Ok(self)
    }

    /// Stops after `max_frames` kept frames.
    ///
    /// # Errors
    /// `max_frames` = 0.
    pub fn max_frames(mut self, max_frames: usize) -> Result<Input, Error> {
        if max_frames == 0 {
            return Err(Error::InvalidOption {
                name: "--max-frames",
                value: "0".into(),
                reason: "must be at least 1",
            });
        }
        self.max_frames = Some(max_frames);
        Ok(self)
    }

    /// Starts after input frame `index`: the kept frames up to it were processed by an earlier
    /// run, and still count towards [`Input::max_frames`]. An image folder's earlier files are
    /// not read; a video's earlier frames are decoded and dropped.
    pub fn after(mut self, index: usize) -> Input {
        self.after = Some(index);
        self.kept = index / self.every + 1;
        if let FrameSource::Images { paths, next, .. } = &mut self.source {
            *next = (index + 1).min(paths.len());
        }
        self
    }

    /// Which frames are kept.
    pub fn selection(&self) -> FrameSelection {
        FrameSelection {
            every: self.every,
            max_frames: self.max_frames,
        }
    }

    /// Copies every kept frame `select` chooses into `into` as it is decoded.
    pub fn keep_copies(
        mut self,
        select: impl FnMut(&Frame) -> bool + Send + 'static,
        into: KeptFrames,
    ) -> Input {
        self.copies = Some((Box::new(select), into));
        self
    }

    /// Ends the input before its next frame once `stop` is set, so that a run stops cleanly:
    /// the frames already read go through every stage and are written.
    pub fn stop_on(mut self, stop: Arc<AtomicBool>) -> Input {
        self.stop = Some(stop);
        self
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Frame size in pixels (display orientation).
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// How many frames will be kept, when the input's length is known.
    pub fn frames_to_process(&self) -> Option<usize> {
        let n = self.frame_count?.div_ceil(self.every);
        let done = self.after.map_or(0, |index| index / self.every + 1);
        Some(self.max_frames.map_or(n, |m| n.min(m)).saturating_sub(done))
    }

    /// Frames per second of the input (a video's stream rate; none for images).
    pub fn frame_rate(&self) -> Option<f64> {
        self.source.frame_rate()
    }

    /// The 35 mm-equivalent focal length (mm) in the EXIF of an image input's first image, and
    /// that image's path.
    pub fn exif_focal_35mm(&self) -> Option<(PathBuf, f64)> {
        match &self.source {
            FrameSource::Images { paths, .. } => {
                let first = paths.first()?;
                focal_length_35mm(first).map(|f| (first.clone(), f))
            }
            FrameSource::Video(_) | FrameSource::Generated { .. } => None,
        }
    }
}

/// A kept frame and the milliseconds spent decoding it (and the skipped frames before it).
pub(crate) struct Decoded {
    pub frame: Frame,
    pub decode_ms: f64,
}

impl Input {
    /// The next kept frame with its decoding time, `None` at the end.
    pub(crate) fn next_decoded(&mut self) -> Option<Result<Decoded, Error>> {
        let mut decode_ms = 0.0;
        loop {
            if self.max_frames.is_some_and(|m| self.kept >= m)
                || self.stop.as_ref().is_some_and(|s| s.load(Ordering::SeqCst))
            {
                return None;
            }
            let t = std::time::Instant::now();
            let frame = self.source.next()?;
            decode_ms += t.elapsed().as_secs_f64() * 1e3;
            let frame = match frame {
                Ok(f) => f,
                Err(e) => return Some(Err(e.into())),
            };
            if frame.index % self.every != 0 || self.after.is_some_and(|a| frame.index <= a) {
                if let Some(pool) = &self.pool {
                    pool.recycle(frame);
                }
                continue;
            }
            self.kept += 1;
            if let Some((select, into)) = &mut self.copies {
                if select(&frame) {
                    if let Ok(mut v) = into.0.lock() {
                        v.push(frame.clone());
                    }
                }
            }
            return Some(Ok(Decoded { frame, decode_ms }));
        }
    }
}

impl Iterator for Input {
    type Item = Result<Frame, Error>;

    fn next(&mut self) -> Option<Self::Item> {
        self.next_decoded().map(|d| d.map(|d| d.frame))
    }
}
