//! Video encoding through the `ffmpeg` command-line tool: RGB8 frames through a pipe into
//! H.264 (libx264, yuv420p, CRF 23, preset veryfast) in an MP4 with its index at the front
//! (`+faststart`, so a browser starts playing before the whole file is loaded), optionally with
//! the sound of another file from a given time (AAC; [`AudioTrack`]), so lip sync can be
//! checked.
//!
//! The video is written to a temporary file beside the target (`preview.tmp.mp4` for
//! `preview.mp4`) and renamed into place only when ffmpeg has exited successfully, so an
//! interrupted or failed encode never leaves a half-written file under the final name (and a
//! dropped, unfinished writer removes its temporary file).
//!
//! Why the command-line tool: the same reasons as for decoding (see the crate's docs) — no C
//! libraries to build against, and an encoder crash cannot take the process down.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::thread::JoinHandle;

use image::RgbImage;

use crate::VideoError;

/// The sound a video gets: the first audio stream of `path` from `start_s` seconds on, cut at
/// the video's end. A file without sound gives a silent video.
#[derive(Clone, Copy, Debug)]
pub struct AudioTrack<'a> {
    pub path: &'a Path,
    pub start_s: f64,
}

/// Writes RGB8 frames of one size to an H.264 MP4 (see the module's docs).
///
/// ```no_run
/// # fn main() -> Result<(), visage_video::VideoError> {
/// let mut writer = visage_video::VideoWriter::create("out.mp4".as_ref(), 640, 480, 30.0)?;
/// writer.write_frame(&image::RgbImage::new(640, 480))?;
/// writer.finish()?;
/// # Ok(()) }
/// ```
pub struct VideoWriter {
    path: PathBuf,
    tmp: PathBuf,
    width: u32,
    height: u32,
    child: Option<Child>,
    stdin: Option<ChildStdin>,
    stderr: Option<JoinHandle<String>>,
    frames: usize,
}

impl VideoWriter {
    /// Starts `ffmpeg` writing a `width × height` video at `fps` frames per second to `path`
    /// (through its temporary file). The size must be even in both directions (yuv420p halves
    /// the colour resolution): pad the frames, this writer does not.
    ///
    /// # Errors
    /// [`VideoError::Encode`] for an odd or zero size or a frame rate that is not positive and
    /// finite; [`VideoError::ToolMissing`] when `ffmpeg` cannot be started.
    pub fn create(
        path: &Path,
        width: u32,
        height: u32,
        fps: f64,
    ) -> Result<VideoWriter, VideoError> {
        VideoWriter::create_with_audio(path, width, height, fps, None)
    }

    /// [`VideoWriter::create`] with the sound of `audio` (none: a silent video).
    ///
    /// # Errors
    /// As [`VideoWriter::create`]; a sound file ffmpeg cannot read fails the encode, reported by
    /// [`VideoWriter::finish`].
    pub fn create_with_audio(
        path: &Path,
        width: u32,
        height: u32,
        fps: f64,
        audio: Option<AudioTrack>,
    ) -> Result<VideoWriter, VideoError> {
        let refuse = |reason: String| VideoError::Encode {
            path: path.to_owned(),
            reason,
        };
        if width == 0 || height == 0 || !width.is_multiple_of(2) || !height.is_multiple_of(2) {
            return Err(refuse(format!(
                "the frame size must be even and non-zero in both directions (H.264 in yuv420p), not {width}×{height}"
            )));
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(refuse(format!(
                "the frame rate must be positive and finite, not {fps}"
            )));
        }
        let tmp = temporary_path(path);
        let mut command = Command::new("ffmpeg");
        command
            .args(["-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24"])
            .args(["-s", &format!("{width}x{height}"), "-r", &rate_string(fps)])
            .args(["-i", "-"]);
        match audio {
            Some(track) => {
                // The sound's first stream if it has one ('?'), cut at the video's end.
                command
                    .args(["-ss", &format!("{:.6}", track.start_s.max(0.0)), "-i"])
                    .arg(track.path)
                    .args([
                        "-map", "0:v:0", "-map", "1:a:0?", "-c:a", "aac", "-b:a", "128k",
                    ])
                    .arg("-shortest");
            }
            None => {
                command.arg("-an");
            }
        }
        let mut child = command
            .args(["-c:v", "libx264", "-pix_fmt", "yuv420p"])
            .args([
                "-crf",
                "23",
                "-preset",
                "veryfast",
                "-movflags",
                "+faststart",
            ])
            .args(["-f", "mp4"])
            .arg(&tmp)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| VideoError::ToolMissing {
                path: path.to_owned(),
                tool: "ffmpeg",
                reason: e.to_string(),
            })?;
        let stdin = child.stdin.take();
        let stderr = crate::ffmpeg::collect_stderr(&mut child);
        Ok(VideoWriter {
            path: path.to_owned(),
            tmp,
            width,
            height,
            child: Some(child),
            stdin,
            stderr,
            frames: 0,
        })
    }

    /// The file the video ends up in.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Frame width, pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Frame height, pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Frames written so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Appends one frame of the writer's size.
    ///
    /// # Errors
    /// [`VideoError::Encode`]: another size, or ffmpeg stopped reading (its message included).
    pub fn write_frame(&mut self, image: &RgbImage) -> Result<(), VideoError> {
        if image.dimensions() != (self.width, self.height) {
            return Err(VideoError::Encode {
                path: self.path.clone(),
                reason: format!(
                    "frame {} is {}×{}, the video is {}×{}",
                    self.frames,
                    image.width(),
                    image.height(),
                    self.width,
                    self.height
                ),
            });
        }
        self.write_rgb(image.as_raw())
    }

    /// Appends one frame given as packed RGB8 rows (`width · height · 3` bytes).
    ///
    /// # Errors
    /// As [`VideoWriter::write_frame`].
    pub fn write_rgb(&mut self, rgb: &[u8]) -> Result<(), VideoError> {
        let expected = self.width as usize * self.height as usize * 3;
        if rgb.len() != expected {
            return Err(VideoError::Encode {
                path: self.path.clone(),
                reason: format!(
                    "frame {} has {} bytes, a {}×{} RGB frame has {expected}",
                    self.frames,
                    rgb.len(),
                    self.width,
                    self.height
                ),
            });
        }
        let written = match self.stdin.as_mut() {
            Some(stdin) => stdin.write_all(rgb),
            None => Err(std::io::Error::other("the encoder has already stopped")),
        };
        match written {
            Ok(()) => {
                self.frames += 1;
                Ok(())
            }
            Err(e) => {
                let (_, stderr) = self.wait();
                Err(VideoError::Encode {
                    path: self.path.clone(),
                    reason: with_stderr(
                        format!("ffmpeg stopped reading at frame {}: {e}", self.frames),
                        &stderr,
                    ),
                })
            }
        }
    }

    /// Closes the stream, waits for ffmpeg and moves the video into place. Returns the number of
    /// frames written.
    ///
    /// # Errors
    /// [`VideoError::Encode`]: no frame was written, ffmpeg failed (its message included), or
    /// the temporary file could not be renamed.
    pub fn finish(mut self) -> Result<usize, VideoError> {
        let path = self.path.clone();
        let encode_error = |reason: String| VideoError::Encode { path, reason };
        if self.frames == 0 {
            return Err(encode_error("no frames to encode".into()));
        }
        let (status, stderr) = self.wait();
        match status {
            Some(s) if s.success() => {}
            Some(s) => {
                return Err(encode_error(with_stderr(
                    format!("ffmpeg failed ({s})"),
                    &stderr,
                )))
            }
            None => {
                return Err(encode_error(with_stderr(
                    "ffmpeg could not be waited for".into(),
                    &stderr,
                )))
            }
        }
        std::fs::rename(&self.tmp, &self.path).map_err(|e| {
            encode_error(format!(
                "cannot move {} into place: {e}",
                self.tmp.display()
            ))
        })?;
        Ok(self.frames)
    }

    /// Closes ffmpeg's input and waits for it: its exit status (`None` when already waited for
    /// or not waitable) and what it wrote to stderr.
    fn wait(&mut self) -> (Option<std::process::ExitStatus>, String) {
        self.stdin = None;
        let status = self.child.take().and_then(|mut c| c.wait().ok());
        let stderr = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        (status, stderr)
    }
}

impl Drop for VideoWriter {
    /// An unfinished writer stops ffmpeg and removes the temporary file.
    fn drop(&mut self) {
        self.stdin = None;
        if let Some(mut c) = self.child.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
        if let Some(h) = self.stderr.take() {
            let _ = h.join();
        }
        if self.tmp.exists() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// `dir/name.tmp.ext` beside `dir/name.ext` (`dir/name.tmp` without an extension).
fn temporary_path(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match path.extension() {
        Some(ext) => format!("{stem}.tmp.{}", ext.to_string_lossy()),
        None => format!("{stem}.tmp"),
    };
    path.with_file_name(name)
}

/// The frame rate as ffmpeg's `-r` takes it: an exact ratio for whole rates and the NTSC ones
/// (`30000/1001` for 29.97), else the decimal value.
fn rate_string(fps: f64) -> String {
    let whole = fps.round();
    if (fps - whole).abs() < 1e-6 * fps {
        return format!("{}", whole as u64);
    }
    let ntsc = (fps * 1.001).round();
    if (fps - ntsc / 1.001).abs() < 1e-4 * fps {
        return format!("{}/1001", ntsc as u64 * 1000);
    }
    format!("{fps:.6}")
}

/// `message`, then ffmpeg's last non-empty stderr lines (up to 5), if any.
fn with_stderr(message: String, stderr: &str) -> String {
    let lines: Vec<&str> = stderr
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    if lines.is_empty() {
        return message;
    }
    let tail = &lines[lines.len().saturating_sub(5)..];
    format!("{message}: {}", tail.join(" | "))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::FrameSource;

    #[test]
    fn sizes_rates_and_names() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("v.mp4");
        for (w, h) in [(63, 48), (64, 47), (0, 48)] {
            let err = VideoWriter::create(&path, w, h, 30.0).err().unwrap();
            assert!(matches!(err, VideoError::Encode { .. }), "{err}");
            assert!(err.to_string().contains("v.mp4"), "{err}");
        }
        assert!(VideoWriter::create(&path, 64, 48, f64::NAN).is_err());
        assert_eq!(rate_string(30.0), "30");
        assert_eq!(rate_string(30000.0 / 1001.0), "30000/1001");
        assert_eq!(rate_string(24000.0 / 1001.0), "24000/1001");
        assert_eq!(rate_string(12.5), "12.500000");
        assert_eq!(
            temporary_path(Path::new("a/preview.mp4")),
            PathBuf::from("a/preview.tmp.mp4")
        );
        assert_eq!(
            temporary_path(Path::new("a/preview")),
            PathBuf::from("a/preview.tmp")
        );
        assert_eq!(with_stderr("m".into(), "\n a \n\nb\n"), "m: a | b");
        assert_eq!(with_stderr("m".into(), " \n"), "m");
    }

    /// The colour of frame `i` of the round trip.
    fn colour(i: usize) -> [u8; 3] {
        [40 + 20 * i as u8, 200 - 15 * i as u8, 90]
    }

    #[test]
    #[cfg_attr(not(ffmpeg), ignore = "needs FFmpeg")]
    fn frames_round_trip_through_ffmpeg() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("round_trip.mp4");
        let (w, h, n) = (96u32, 64u32, 8usize);
        let mut writer = VideoWriter::create(&path, w, h, 25.0).unwrap();
        assert!(
            writer.write_frame(&RgbImage::new(w + 2, h)).is_err(),
            "a frame of another size is refused"
        );
        for i in 0..n {
            let c = colour(i);
            // A solid colour with a light square in the middle, so the encoder sees structure.
            let image = RgbImage::from_fn(w, h, |x, y| {
                let inner = (32..64).contains(&x) && (16..48).contains(&y);
                image::Rgb(if inner { [230, 230, 230] } else { c })
            });
            writer.write_frame(&image).unwrap();
        }
        assert_eq!(writer.frames(), n);
        assert_eq!(writer.finish().unwrap(), n);
        assert!(path.is_file());
        assert!(
            !dir.path().join("round_trip.tmp.mp4").exists(),
            "the temporary file is renamed into place"
        );

        let frames: Vec<_> = FrameSource::open(&path)
            .unwrap()
            .collect::<Result<_, _>>()
            .unwrap();
        assert_eq!(frames.len(), n);
        for (i, f) in frames.iter().enumerate() {
            assert_eq!(f.image.dimensions(), (w, h));
            let t = f.timestamp_s.unwrap();
            assert!((t - i as f64 / 25.0).abs() < 1e-3, "frame {i} at {t} s");
            // Mean colour of the outer band (rows 0–7), away from the square's edges.
            let mut sum = [0.0f64; 3];
            let mut count = 0.0;
            for y in 0..8 {
                for x in 0..w {
                    let p = f.image.get_pixel(x, y).0;
                    for c in 0..3 {
                        sum[c] += p[c] as f64;
                    }
                    count += 1.0;
                }
            }
            let expected = colour(i);
            for c in 0..3 {
                let mean = sum[c] / count;
                assert!(
                    (mean - expected[c] as f64).abs() < 4.0,
                    "frame {i} channel {c}: mean {mean:.1}, wrote {}",
                    expected[c]
                );
            }
        }
    }

    #[test]
    #[cfg_attr(not(ffmpeg), ignore = "needs FFmpeg")]
    fn a_failed_encode_names_the_file_and_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        // ffmpeg cannot create a file in a folder that does not exist.
        let path = dir.path().join("missing/out.mp4");
        let mut writer = VideoWriter::create(&path, 16, 16, 30.0).unwrap();
        let frame = RgbImage::new(16, 16);
        let result = (0..4)
            .try_for_each(|_| writer.write_frame(&frame))
            .and_then(|()| writer.finish().map(|_| ()));
        let err = result.unwrap_err();
        assert!(matches!(err, VideoError::Encode { .. }), "{err}");
        let text = err.to_string();
        assert!(text.contains("out.mp4"), "{text}");
        assert!(!path.exists());

        // Dropping an unfinished writer removes its temporary file.
        let path = dir.path().join("dropped.mp4");
        let mut writer = VideoWriter::create(&path, 16, 16, 30.0).unwrap();
        writer.write_frame(&frame).unwrap();
        drop(writer);
        assert!(!path.exists() && !dir.path().join("dropped.tmp.mp4").exists());
        // And finishing without frames is refused.
        let writer = VideoWriter::create(&path, 16, 16, 30.0).unwrap();
        assert!(writer.finish().is_err());
    }
}
