//! Video decoding through the FFmpeg command-line tools: `ffprobe` for size, frame rate and
//! rotation; `ffmpeg -f rawvideo -pix_fmt rgb24 -` through a pipe, one frame in memory at a time.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::thread::JoinHandle;

use image::RgbImage;

use crate::{Frame, VideoError};

/// What `ffprobe` reports about the first video stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VideoInfo {
    /// Displayed width in pixels (after the rotation metadata is applied).
    pub width: u32,
    /// Displayed height in pixels.
    pub height: u32,
    /// Frames per second (`r_frame_rate`), `None` when unknown.
    pub fps: Option<f64>,
    /// Rotation metadata in degrees (counter-clockwise, as FFmpeg's display matrix), 0 if none.
    pub rotation: i32,
    /// Frame count from the container, when it states one.
    pub frame_count: Option<usize>,
}

/// Probes `path` with `ffprobe`.
pub fn probe(path: &Path) -> Result<VideoInfo, VideoError> {
    let out = Command::new("ffprobe")
        .args([
            "-v",
            "error",
            "-select_streams",
            "v:0",
            "-show_streams",
            "-of",
            "json",
        ])
        .arg(path)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| VideoError::ToolMissing {
            path: path.to_owned(),
            tool: "ffprobe",
            reason: e.to_string(),
        })?;
    let not_video = |reason: String| VideoError::NotVideo {
        path: path.to_owned(),
        reason,
    };
    if !out.status.success() {
        return Err(not_video(
            String::from_utf8_lossy(&out.stderr).trim().to_owned(),
        ));
    }
    let v: serde_json::Value = serde_json::from_slice(&out.stdout)
        .map_err(|e| not_video(format!("unexpected ffprobe output: {e}")))?;
    let s = v["streams"]
        .get(0)
        .ok_or_else(|| not_video("no video stream".into()))?;
    let dim = |k: &str| {
        s[k].as_u64()
            .filter(|&d| d > 0 && d <= u32::MAX as u64)
            .map(|d| d as u32)
    };
    let (Some(w), Some(h)) = (dim("width"), dim("height")) else {
        return Err(not_video("video stream without a size".into()));
    };
    let fps = s["r_frame_rate"].as_str().and_then(|r| {
        let (a, b) = r.split_once('/')?;
        let (a, b): (f64, f64) = (a.parse().ok()?, b.parse().ok()?);
        (a > 0.0 && b > 0.0).then_some(a / b)
    });
    let rotation = s["side_data_list"]
        .as_array()
        .and_then(|l| l.iter().find_map(|d| d["rotation"].as_i64()))
        .or_else(|| s["tags"]["rotate"].as_str().and_then(|r| r.parse().ok()))
        .unwrap_or(0) as i32;
    let frame_count = s["nb_frames"].as_str().and_then(|n| n.parse().ok());
    let quarter = rotation.rem_euclid(180) == 90;
    Ok(VideoInfo {
        width: if quarter { h } else { w },
        height: if quarter { w } else { h },
        fps,
        rotation,
        frame_count,
    })
}

/// Streams the frames of a video. Yields `Ok(frame)` for every decodable frame; if the
/// stream breaks (truncated or corrupt file) the last item is `Err(VideoError::Broken)` naming
/// the frame where it broke.
pub struct VideoReader {
    path: PathBuf,
    info: VideoInfo,
    child: Option<Child>,
    stdout: Option<ChildStdout>,
    stderr: Option<JoinHandle<String>>,
    next: usize,
    done: bool,
}

impl VideoReader {
    /// Probes and starts decoding `path`.
    pub fn open(path: &Path) -> Result<VideoReader, VideoError> {
        let info = probe(path)?;
        let mut child = Command::new("ffmpeg")
            .args(["-v", "error", "-nostdin", "-i"])
            .arg(path)
            .args(["-map", "0:v:0", "-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| VideoError::ToolMissing {
                path: path.to_owned(),
                tool: "ffmpeg",
                reason: e.to_string(),
            })?;
        let stdout = child.stdout.take();
        let stderr = child.stderr.take().map(|mut e| {
            std::thread::spawn(move || {
                let mut s = String::new();
                let _ = e.read_to_string(&mut s);
                s
            })
        });
        Ok(VideoReader {
            path: path.to_owned(),
            info,
            child: Some(child),
            stdout,
            stderr,
            next: 0,
            done: false,
        })
    }

    /// Size, frame rate and rotation of the stream.
    pub fn info(&self) -> VideoInfo {
        self.info
    }

    /// Waits for ffmpeg and turns a failure into `Broken`; `None` when it ended cleanly.
    fn finish(&mut self, partial: bool) -> Option<VideoError> {
        self.done = true;
        self.stdout = None;
        let status = self.child.take().and_then(|mut c| c.wait().ok());
        let stderr = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        let failed = status.is_none_or(|s| !s.success());
        let decode_errors = !stderr.trim().is_empty();
        if partial || failed || decode_errors {
            let mut reason = stderr
                .lines()
                .rev()
                .find(|l| !l.trim().is_empty())
                .unwrap_or("")
                .trim()
                .to_owned();
            if partial {
                reason = format!("incomplete frame data at the end of the stream {reason}")
                    .trim()
                    .to_owned();
            }
            if reason.is_empty() {
                reason = format!("ffmpeg exited with {status:?}");
            }
            return Some(VideoError::Broken {
                path: self.path.clone(),
                frame: self.next,
                reason,
            });
        }
        None
    }
}

impl Iterator for VideoReader {
    type Item = Result<Frame, VideoError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let (w, h) = (self.info.width, self.info.height);
        let mut buf = vec![0u8; w as usize * h as usize * 3];
        let mut filled = 0;
        if let Some(out) = self.stdout.as_mut() {
            while filled < buf.len() {
                match out.read(&mut buf[filled..]) {
                    Ok(0) => break,
                    Ok(n) => filled += n,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                    Err(_) => break,
                }
            }
        }
        if filled < buf.len() {
            return self.finish(filled > 0).map(Err);
        }
        let image = RgbImage::from_raw(w, h, buf)?;
        let frame = Frame {
            index: self.next,
            source: format!("{}:{}", self.path.display(), self.next),
            image,
        };
        self.next += 1;
        Some(Ok(frame))
    }
}

impl Drop for VideoReader {
    fn drop(&mut self) {
        self.stdout = None;
        if let Some(mut c) = self.child.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// Whether `ffmpeg` and `ffprobe` can be run (for tests and diagnostics).
pub fn ffmpeg_available() -> bool {
    ["ffmpeg", "ffprobe"].iter().all(|t| {
        Command::new(t)
            .arg("-version")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    })
}
