//! Frames as they arrive from a live source — a camera, a network stream, standard input, or a
//! file played at its own pace — through FFmpeg, with a queue of one where the newest frame
//! wins: when the reader falls behind, the frame it did not take is dropped and counted, never
//! queued. One FFmpeg process decodes the source to RGB; its size is read from FFmpeg's own
//! description of its output stream, so any source FFmpeg opens works without a separate probe
//! (standard input cannot be probed twice).

use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use image::RgbImage;

use crate::{Frame, VideoError};

/// A frame and when it was read from FFmpeg (its capture time, as near as visage sees it).
#[derive(Clone, Debug)]
pub struct CapturedFrame {
    pub frame: Frame,
    pub captured_at: Instant,
}

/// How the source is read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LiveOptions {
    /// Play a file at its own frame rate (FFmpeg's `-re`), as a camera would deliver it.
    pub realtime: bool,
    /// End the source when no frame has come for this long after the first one: a network
    /// stream (MPEG-TS over UDP, say) has no end of its own, its sender just stops (`None`:
    /// wait for FFmpeg to end it).
    pub idle_end: Option<Duration>,
}

/// The newest frame not yet taken, and the counts.
#[derive(Default)]
struct Slot {
    frame: Option<CapturedFrame>,
    /// The source ended (`Some(Ok)`) or broke.
    ended: Option<Result<(), String>>,
    captured: usize,
    dropped: usize,
    /// When the last frame was read.
    last_at: Option<Instant>,
}

/// A live source being read.
pub struct LiveCapture {
    source: String,
    width: u32,
    height: u32,
    started: Instant,
    shared: Arc<(Mutex<Slot>, Condvar)>,
    child: Mutex<Child>,
    /// FFmpeg's last message (the reason when the source breaks).
    last_message: Arc<Mutex<String>>,
    reader: Option<JoinHandle<()>>,
    idle_end: Option<Duration>,
    /// Whether the source was ended for its silence ([`LiveOptions::idle_end`]).
    went_quiet: std::sync::atomic::AtomicBool,
}

/// How long FFmpeg looks at a network stream before its first frame, microseconds.
const NETWORK_ANALYZE_US: &str = "500000";

/// How FFmpeg is told to open `source`: a V4L2 camera (`/dev/videoN`), standard input (`-`), or
/// anything else FFmpeg opens by name (a file, `udp://`, `rtsp://`, `http://`, `srt://`).
fn input_args(source: &str, options: &LiveOptions) -> Vec<String> {
    let mut args = Vec::new();
    if source.starts_with("/dev/video") {
        args.extend(["-f", "v4l2"].map(String::from));
    }
    if options.realtime {
        args.push("-re".into());
    }
    if source.contains("://") {
        // FFmpeg reads 5 s of a stream before its first frame by default, then gives those
        // frames at once (on MPEG-TS over UDP from a 7 s clip: the first frame after 6.1 s, 150
        // of 208 within 5 ms of the one before); half a second finds the stream's size and the
        // frames then come at their pace (the first after 0.6 s, 11 close together).
        args.extend(["-analyzeduration", NETWORK_ANALYZE_US].map(String::from));
    }
    args.push("-i".into());
    args.push(if source == "-" { "pipe:0" } else { source }.into());
    args
}

/// The size of the raw video stream FFmpeg writes, from its description
/// (`Stream #0:0: Video: rawvideo (RGB[24] / 0x18424752), rgb24(…), 640x480, …`).
fn output_size(line: &str) -> Option<(u32, u32)> {
    if !(line.contains("Video: rawvideo") && line.contains("rgb24")) {
        return None;
    }
    line.split([',', ' ']).find_map(|word| {
        let (w, h) = word.split_once('x')?;
        Some((w.parse().ok()?, h.parse().ok()?)).filter(|&(w, h)| w > 0 && h > 0)
    })
}

impl LiveCapture {
    /// Starts FFmpeg on `source` and waits until it says what it decodes to.
    ///
    /// # Errors
    /// FFmpeg is missing, or ends before giving a video stream (the source cannot be opened:
    /// its last message is the reason).
    pub fn open(source: &str, options: &LiveOptions) -> Result<LiveCapture, VideoError> {
        let path = std::path::PathBuf::from(source);
        let mut child = Command::new("ffmpeg")
            .args(["-hide_banner", "-nostats", "-v", "info"])
            .args(input_args(source, options))
            .args([
                "-map", "0:v:0", "-f", "rawvideo", "-pix_fmt", "rgb24", "pipe:1",
            ])
            .stdin(if source == "-" {
                Stdio::inherit()
            } else {
                Stdio::null()
            })
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| VideoError::ToolMissing {
                path: path.clone(),
                tool: "ffmpeg",
                reason: e.to_string(),
            })?;
        let mut stderr = BufReader::new(child.stderr.take().expect("piped"));
        let mut last = String::new();
        let mut in_output = false;
        let size = loop {
            let mut line = String::new();
            match stderr.read_line(&mut line) {
                Ok(0) | Err(_) => break None,
                Ok(_) => {}
            }
            in_output |= line.starts_with("Output #0");
            if in_output {
                if let Some(size) = output_size(&line) {
                    break Some(size);
                }
            }
            if !line.trim().is_empty() {
                last = line.trim().to_owned();
            }
        };
        let Some((width, height)) = size else {
            let _ = child.kill();
            let _ = child.wait();
            return Err(VideoError::NotVideo {
                path,
                reason: format!("FFmpeg could not read it as a live video source: {last}"),
            });
        };
        // The rest of FFmpeg's messages: the last one is kept as the reason a source broke.
        let last_message = Arc::new(Mutex::new(String::new()));
        let messages = last_message.clone();
        std::thread::spawn(move || {
            for line in stderr.lines().map_while(Result::ok) {
                if !line.trim().is_empty() {
                    *messages.lock().unwrap_or_else(|e| e.into_inner()) = line.trim().to_owned();
                }
            }
        });
        let shared = Arc::new((Mutex::new(Slot::default()), Condvar::new()));
        let stdout = child.stdout.take().expect("piped");
        let started = Instant::now();
        let reader = {
            let shared = shared.clone();
            let source = source.to_owned();
            std::thread::spawn(move || {
                read_frames(stdout, width, height, &source, started, &shared)
            })
        };
        Ok(LiveCapture {
            source: source.to_owned(),
            width,
            height,
            started,
            shared,
            child: Mutex::new(child),
            last_message,
            reader: Some(reader),
            idle_end: options.idle_end,
            went_quiet: std::sync::atomic::AtomicBool::new(false),
        })
    }

    /// The frames' size, pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The source as given.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// When reading started (frames' timestamps count from here).
    pub fn started(&self) -> Instant {
        self.started
    }

    /// The newest frame not yet taken, waiting for one; `Ok(None)` once the source ended.
    ///
    /// # Errors
    /// The source broke (FFmpeg's last message says why).
    pub fn next(&self) -> Result<Option<CapturedFrame>, VideoError> {
        let (lock, ready) = &*self.shared;
        let mut slot = lock.lock().unwrap_or_else(|e| e.into_inner());
        loop {
            if let Some(frame) = slot.frame.take() {
                return Ok(Some(frame));
            }
            match &slot.ended {
                Some(Ok(())) => {
                    // The stream ended: cleanly if FFmpeg says so by its exit status.
                    let mut child = self.child.lock().unwrap_or_else(|e| e.into_inner());
                    let clean = child.wait().is_ok_and(|s| s.success());
                    if clean {
                        return Ok(None);
                    }
                    let reason = self
                        .last_message
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .clone();
                    return Err(VideoError::Broken {
                        path: self.source.clone().into(),
                        frame: slot.captured,
                        reason,
                    });
                }
                Some(Err(reason)) => {
                    return Err(VideoError::Broken {
                        path: self.source.clone().into(),
                        frame: slot.captured,
                        reason: reason.clone(),
                    })
                }
                None => match (self.idle_end, slot.last_at) {
                    (Some(idle), Some(last)) => {
                        let Some(left) = idle.checked_sub(last.elapsed()) else {
                            // Quiet for too long: the stream is over.
                            self.went_quiet
                                .store(true, std::sync::atomic::Ordering::SeqCst);
                            let mut child = self.child.lock().unwrap_or_else(|e| e.into_inner());
                            let _ = child.kill();
                            return Ok(None);
                        };
                        slot = ready
                            .wait_timeout(slot, left)
                            .unwrap_or_else(|e| e.into_inner())
                            .0;
                    }
                    _ => slot = ready.wait(slot).unwrap_or_else(|e| e.into_inner()),
                },
            }
        }
    }

    /// Whether the source ended because no frame came for [`LiveOptions::idle_end`].
    pub fn went_quiet(&self) -> bool {
        self.went_quiet.load(std::sync::atomic::Ordering::SeqCst)
    }

    /// Frames read from the source so far, and of them those dropped because a newer one
    /// arrived before they were taken.
    pub fn counts(&self) -> (usize, usize) {
        let slot = self.shared.0.lock().unwrap_or_else(|e| e.into_inner());
        (slot.captured, slot.dropped)
    }
}

impl Drop for LiveCapture {
    fn drop(&mut self) {
        let child = self.child.get_mut().unwrap_or_else(|e| e.into_inner());
        let _ = child.kill();
        let _ = child.wait();
        if let Some(reader) = self.reader.take() {
            let _ = reader.join();
        }
    }
}

/// Reads FFmpeg's raw frames into the slot until the stream ends.
fn read_frames(
    mut stdout: impl Read,
    width: u32,
    height: u32,
    source: &str,
    started: Instant,
    shared: &(Mutex<Slot>, Condvar),
) {
    let (lock, ready) = shared;
    let bytes = width as usize * height as usize * 3;
    let mut index = 0;
    let ended = loop {
        // Straight into the frame's allocation, without zero-filling it first.
        let mut buffer = Vec::with_capacity(bytes);
        match stdout.by_ref().take(bytes as u64).read_to_end(&mut buffer) {
            Ok(n) if n == bytes => {}
            Ok(_) => break Ok(()),
            Err(e) => break Err(e.to_string()),
        }
        let captured_at = Instant::now();
        let image = RgbImage::from_raw(width, height, buffer).expect("sized to the frame");
        let frame = Frame {
            index,
            source: format!("{source}:{index}"),
            timestamp_s: Some(captured_at.duration_since(started).as_secs_f64()),
            image,
        };
        index += 1;
        let mut slot = lock.lock().unwrap_or_else(|e| e.into_inner());
        if slot.frame.is_some() {
            slot.dropped += 1;
        }
        slot.frame = Some(CapturedFrame { frame, captured_at });
        slot.captured += 1;
        slot.last_at = Some(captured_at);
        ready.notify_one();
    };
    // A stream that ends part-way through a frame is cut off (the short frame is dropped, and
    // FFmpeg's exit status tells the rest).
    let mut slot = lock.lock().unwrap_or_else(|e| e.into_inner());
    slot.ended = Some(ended);
    ready.notify_all();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_output_size_is_read_from_ffmpegs_stream_line() {
        let line = "  Stream #0:0: Video: rawvideo (RGB[24] / 0x18424752), rgb24(pc, gbr/unknown/unknown, \
                    progressive), 480x480 [SAR 1:1 DAR 1:1], q=2-31, 165888 kb/s, 30 fps, 30 tbn";
        assert_eq!(output_size(line), Some((480, 480)));
        let input =
            "  Stream #0:0(und): Video: h264 (High) (avc1 / 0x31637661), yuv420p(tv, bt709, \
                     progressive), 720x1280, 2001 kb/s, 30 fps";
        assert_eq!(output_size(input), None);
    }

    #[test]
    fn a_camera_is_opened_with_v4l2_and_standard_input_as_a_pipe() {
        let live = LiveOptions {
            realtime: true,
            idle_end: None,
        };
        assert_eq!(
            input_args("/dev/video0", &LiveOptions::default()),
            ["-f", "v4l2", "-i", "/dev/video0"]
        );
        assert_eq!(input_args("-", &LiveOptions::default()), ["-i", "pipe:0"]);
        assert_eq!(input_args("clip.mp4", &live), ["-re", "-i", "clip.mp4"]);
        assert_eq!(
            input_args("udp://127.0.0.1:5000", &LiveOptions::default()),
            ["-analyzeduration", "500000", "-i", "udp://127.0.0.1:5000"]
        );
    }
}
