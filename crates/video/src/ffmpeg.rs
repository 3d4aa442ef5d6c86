//! Video decoding through the FFmpeg command-line tools: `ffprobe` for size, frame rate and
//! rotation; `ffmpeg -f rawvideo -pix_fmt rgb24 -` through a pipe, one frame in memory at a time.
//!
//! # Timestamps
//! Every decoded frame carries its presentation time ([`Frame::timestamp_s`]), in seconds since
//! the first frame. Before decoding, `ffprobe` lists the video packets' presentation timestamps
//! (`-show_entries packet=pts,flags`: the container's index, no decoding, about 0.1 s for a
//! minute of video; in the same run as the stream's size and rate and FFmpeg's release);
//! discarded packets (flag `D`, e.g. before an MP4 edit list's start) are dropped and the rest
//! sorted into presentation order. `ffmpeg` runs with `-fps_mode
//! passthrough` (`-vsync passthrough` before FFmpeg 5.1), so it hands over every decoded frame
//! exactly once, in presentation order — without it the
//! raw-video output is constant-rate and a variable-frame-rate video comes out with frames
//! duplicated or dropped. Frame `i` then has the `i`-th sorted timestamp, so variable frame
//! rates are exact. When the container has no timestamps (a raw elementary stream, a packet
//! without `pts`), or decoding yields more frames than packets were listed, the frame rate
//! stands in: `index / fps`, or one `1 / fps` step per frame after the last listed packet;
//! without a frame rate the timestamp is `None`.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::thread::JoinHandle;

use image::RgbImage;

use crate::{Frame, FramePool, VideoError};

/// What `ffprobe` reports about the first video stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VideoInfo {
    /// Displayed width in pixels (after the rotation metadata is applied).
    pub width: u32,
    /// Displayed height in pixels.
    pub height: u32,
    /// The stream's frame rate in frames per second (`r_frame_rate`, exact as the ratio FFmpeg
    /// states, e.g. 30000/1001 for 29.97), `None` when unknown. For a constant-rate video it
    /// is the rate of its frames; for a variable-rate one, the base rate its timestamps are a
    /// multiple of — use [`Frame::timestamp_s`] for when a frame is shown.
    pub fps: Option<f64>,
    /// The average frame rate (`avg_frame_rate`: frames / duration), `None` when unknown.
    /// Equals `fps` for a constant-rate video.
    pub avg_fps: Option<f64>,
    /// Rotation metadata in degrees (counter-clockwise, as FFmpeg's display matrix), 0 if none.
    pub rotation: i32,
    /// Frame count from the container, when it states one.
    pub frame_count: Option<usize>,
}

/// The stream's time base (seconds per timestamp tick), as FFmpeg's ratio.
#[derive(Clone, Copy, Debug)]
struct TimeBase {
    num: i64,
    den: i64,
}

/// Probes `path` with `ffprobe`.
pub fn probe(path: &Path) -> Result<VideoInfo, VideoError> {
    probe_stream(path).map(|(info, _)| info)
}

/// A ratio `"a/b"` with both parts positive.
fn ratio(s: &serde_json::Value) -> Option<(i64, i64)> {
    let (a, b) = s.as_str()?.split_once('/')?;
    let (a, b): (i64, i64) = (a.trim().parse().ok()?, b.trim().parse().ok()?);
    (a > 0 && b > 0).then_some((a, b))
}

/// Runs `ffprobe` on the first video stream of `path` with the `show` options (what to list
/// and in which format); its errors are captured in the output, not printed.
fn ffprobe_first_video(path: &Path, show: &[&str]) -> std::io::Result<std::process::Output> {
    Command::new("ffprobe")
        .args(["-v", "error", "-select_streams", "v:0"])
        .args(show)
        .arg(path)
        .stdin(Stdio::null())
        .output()
}

/// [`probe`] and the stream's time base.
fn probe_stream(path: &Path) -> Result<(VideoInfo, Option<TimeBase>), VideoError> {
    let out = ffprobe_first_video(path, &["-show_streams", "-of", "json"]).map_err(|e| {
        VideoError::ToolMissing {
            path: path.to_owned(),
            tool: "ffprobe",
            reason: e.to_string(),
        }
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
    stream_info(&v).map_err(not_video)
}

/// The size, rates, rotation, frame count and time base of `ffprobe`'s first listed stream
/// (its JSON output), or why there is none.
fn stream_info(v: &serde_json::Value) -> Result<(VideoInfo, Option<TimeBase>), String> {
    let s = v["streams"].get(0).ok_or("no video stream")?;
    let dim = |k: &str| {
        s[k].as_u64()
            .filter(|&d| d > 0 && d <= u32::MAX as u64)
            .map(|d| d as u32)
    };
    let (Some(w), Some(h)) = (dim("width"), dim("height")) else {
        return Err("video stream without a size".into());
    };
    let rate = |k: &str| ratio(&s[k]).map(|(a, b)| a as f64 / b as f64);
    let fps = rate("r_frame_rate");
    let avg_fps = rate("avg_frame_rate");
    let time_base = ratio(&s["time_base"]).map(|(num, den)| TimeBase { num, den });
    let rotation = s["side_data_list"]
        .as_array()
        .and_then(|l| l.iter().find_map(|d| d["rotation"].as_i64()))
        .or_else(|| s["tags"]["rotate"].as_str().and_then(|r| r.parse().ok()))
        .unwrap_or(0) as i32;
    let frame_count = s["nb_frames"].as_str().and_then(|n| n.parse().ok());
    let quarter = rotation.rem_euclid(180) == 90;
    let info = VideoInfo {
        width: if quarter { h } else { w },
        height: if quarter { w } else { h },
        fps,
        avg_fps,
        rotation,
        frame_count,
    };
    Ok((info, time_base))
}

/// What [`probe_for_decoding`] found.
struct Probed {
    info: VideoInfo,
    /// The frames' timestamps, seconds since the first.
    timestamps: Option<Vec<f64>>,
    /// FFmpeg's `(major, minor)` release.
    release: Option<(u32, u32)>,
}

/// What decoding needs, from one `ffprobe` run (each run of an FFmpeg tool costs ~50 ms of
/// CPU starting up): the stream ([`probe`]), its frames' timestamps (see the module's docs)
/// and FFmpeg's release (for [`passthrough_option`]; `ffprobe` and `ffmpeg` come from one
/// build). Where that run fails or lists something unexpected, the stream probe and the packet
/// list run separately as before, so a damaged file fails or degrades as it always did.
fn probe_for_decoding(path: &Path) -> Result<Probed, VideoError> {
    let show = [
        "-show_entries",
        "stream:packet=pts,flags",
        "-show_program_version",
        "-of",
        "json",
    ];
    let combined = ffprobe_first_video(path, &show)
        .ok()
        .filter(|out| out.status.success())
        .and_then(|out| serde_json::from_slice::<serde_json::Value>(&out.stdout).ok())
        .and_then(|v| {
            let (info, time_base) = stream_info(&v).ok()?;
            let packets = v["packets"].as_array()?;
            let release = v["program_version"]["version"]
                .as_str()
                .and_then(|version| release(&format!("ffprobe version {version}")));
            Some(Probed {
                info,
                timestamps: time_base.and_then(|tb| packet_times(packets, tb)),
                release,
            })
        });
    match combined {
        Some(found) => Ok(found),
        None => {
            let (info, time_base) = probe_stream(path)?;
            Ok(Probed {
                info,
                timestamps: time_base.and_then(|tb| packet_timestamps(path, tb)),
                release: None,
            })
        }
    }
}

/// [`packet_timestamps`] from the JSON packet list of [`probe_for_decoding`]'s run.
fn packet_times(packets: &[serde_json::Value], time_base: TimeBase) -> Option<Vec<f64>> {
    let mut pts = Vec::with_capacity(packets.len());
    for p in packets {
        if p["flags"].as_str().is_some_and(|f| f.contains('D')) {
            continue;
        }
        pts.push(p["pts"].as_i64()?);
    }
    seconds_since_first(pts, time_base)
}

/// The presentation timestamps of the first video stream's packets, in seconds since the
/// earliest, sorted: the frames' times in the order a passthrough `ffmpeg` delivers them. `None`
/// when `ffprobe` lists no packets or a kept packet has no timestamp. A file cut short lists
/// the packets before the cut.
fn packet_timestamps(path: &Path, time_base: TimeBase) -> Option<Vec<f64>> {
    let out = ffprobe_first_video(
        path,
        &["-show_entries", "packet=pts,flags", "-of", "csv=p=0"],
    )
    .ok()?;
    let pts = parse_packet_list(&String::from_utf8_lossy(&out.stdout))?;
    seconds_since_first(pts, time_base)
}

/// Timestamps `pts` (in `time_base` ticks) sorted, in seconds since the earliest; `None` for
/// none.
fn seconds_since_first(mut pts: Vec<i64>, time_base: TimeBase) -> Option<Vec<f64>> {
    pts.sort_unstable();
    let first = *pts.first()?;
    let tick = time_base.num as f64 / time_base.den as f64;
    Some(pts.iter().map(|&p| (p - first) as f64 * tick).collect())
}

/// The `pts` of each line `pts,flags` that is not flagged discarded (`D`); `None` when a kept
/// line has no integer `pts` (`N/A`).
fn parse_packet_list(text: &str) -> Option<Vec<i64>> {
    let mut pts = Vec::new();
    for line in text.lines().map(str::trim).filter(|l| !l.is_empty()) {
        let mut fields = line.split(',');
        let value = fields.next()?.trim();
        let flags = fields.next().unwrap_or("");
        if flags.contains('D') {
            continue;
        }
        pts.push(value.parse().ok()?);
    }
    Some(pts)
}

/// Streams the frames of a video. Yields `Ok(frame)` for every decodable frame; if the
/// stream breaks (truncated or corrupt file) the last item is `Err(VideoError::Broken)` naming
/// the frame where it broke.
pub struct VideoReader {
    path: PathBuf,
    info: VideoInfo,
    timestamps: Option<Vec<f64>>,
    child: Option<Child>,
    stdout: Option<ChildStdout>,
    stderr: Option<JoinHandle<String>>,
    next: usize,
    done: bool,
    pool: FramePool,
}

impl VideoReader {
    /// Probes `path`, lists its frames' timestamps and starts decoding it.
    pub fn open(path: &Path) -> Result<VideoReader, VideoError> {
        let Probed {
            info,
            timestamps,
            release,
        } = probe_for_decoding(path)?;
        // Every decoded frame once, with its own time (see the module's docs).
        let mut child = Command::new("ffmpeg")
            .args(["-v", "error", "-nostdin", "-i"])
            .arg(path)
            .args(["-map", "0:v:0", passthrough_option(release), "passthrough"])
            .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
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
        let stderr = collect_stderr(&mut child);
        Ok(VideoReader {
            path: path.to_owned(),
            info,
            timestamps,
            child: Some(child),
            stdout,
            stderr,
            next: 0,
            done: false,
            pool: FramePool::default(),
        })
    }

    /// The pool the frames' buffers come from: a frame handed back to it
    /// ([`FramePool::recycle`]) lends its buffer to a later frame.
    pub fn frame_pool(&self) -> FramePool {
        self.pool.clone()
    }

    /// Size, frame rate and rotation of the stream.
    pub fn info(&self) -> VideoInfo {
        self.info
    }

    /// Frame `index`'s presentation time (see the module's docs).
    fn timestamp(&self, index: usize) -> Option<f64> {
        let fps = self.info.fps;
        match self.timestamps.as_deref() {
            Some(ts) if index < ts.len() => Some(ts[index]),
            Some(ts) if !ts.is_empty() => {
                let last = ts.len() - 1;
                fps.map(|f| ts[last] + (index - last) as f64 / f)
            }
            _ => fps.map(|f| index as f64 / f),
        }
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
        let len = w as usize * h as usize * 3;
        // The pipe's bytes go straight into the frame's buffer — one handed back to the pool,
        // else a new allocation — which is never zero-filled first (a 4K frame is 25 MB). A
        // read error ends the frame like an early end of the stream; `finish` then reports
        // what FFmpeg said.
        let mut buf = self.pool.buffer(len);
        if let Some(out) = self.stdout.as_mut() {
            let _ = out.by_ref().take(len as u64).read_to_end(&mut buf);
        }
        if buf.len() < len {
            return self.finish(!buf.is_empty()).map(Err);
        }
        let image = RgbImage::from_raw(w, h, buf)?;
        let frame = Frame {
            index: self.next,
            source: format!("{}:{}", self.path.display(), self.next),
            timestamp_s: self.timestamp(self.next),
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

/// A thread collecting a child's standard error (so a full pipe never blocks it), for the
/// error message when it fails.
pub(crate) fn collect_stderr(child: &mut Child) -> Option<JoinHandle<String>> {
    child.stderr.take().map(|mut e| {
        std::thread::spawn(move || {
            let mut s = String::new();
            let _ = e.read_to_string(&mut s);
            s
        })
    })
}

/// The option that makes `ffmpeg` pass every frame through once: `-fps_mode` (FFmpeg 5.1 and
/// later; FFmpeg 9 dropped the older name), or `-vsync` before 5.1, which has no `-fps_mode`.
/// From `release` where the probe found it, else from `ffmpeg -version`, asked once per
/// process.
fn passthrough_option(release_found: Option<(u32, u32)>) -> &'static str {
    static ASKED: std::sync::OnceLock<Option<(u32, u32)>> = std::sync::OnceLock::new();
    let release_found = release_found.or_else(|| {
        *ASKED.get_or_init(|| {
            let version = Command::new("ffmpeg")
                .arg("-version")
                .stdin(Stdio::null())
                .stderr(Stdio::null())
                .output()
                .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
                .unwrap_or_default();
            release(&version)
        })
    });
    match release_found {
        Some(v) if v < (5, 1) => "-vsync",
        _ => "-fps_mode",
    }
}

/// `(major, minor)` from `ffmpeg -version`'s first line (`ffmpeg version 5.1.9-0+deb12u1 …`,
/// `ffmpeg version n6.1 …`); `None` for a build from git (`N-113000-g…`) or anything else.
fn release(version_text: &str) -> Option<(u32, u32)> {
    let word = version_text
        .split_whitespace()
        .skip_while(|w| *w != "version")
        .nth(1)?;
    let word = word.strip_prefix('n').unwrap_or(word);
    let mut parts = word.split(|c: char| !c.is_ascii_digit());
    let major = parts.next()?.parse().ok()?;
    let minor = parts.next().and_then(|m| m.parse().ok()).unwrap_or(0);
    Some((major, minor))
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

#[cfg(test)]
mod tests {
    use super::{packet_times, parse_packet_list, passthrough_option, release, TimeBase};

    #[test]
    fn ffmpeg_releases_are_read_from_the_version_line() {
        let line =
            |v: &str| format!("ffmpeg version {v} Copyright (c) 2000-2026 the FFmpeg developers");
        assert_eq!(release(&line("5.1.9-0+deb12u1")), Some((5, 1)));
        assert_eq!(release(&line("4.4.2-0ubuntu0.22.04.1")), Some((4, 4)));
        assert_eq!(release(&line("n6.1")), Some((6, 1)));
        assert_eq!(release(&line("9.0-full_build-www.gyan.dev")), Some((9, 0)));
        assert_eq!(release(&line("7")), Some((7, 0)));
        assert_eq!(release(&line("N-113000-g1234abcd")), None);
        assert_eq!(release(""), None);
    }

    #[test]
    fn packet_list_skips_discarded_packets_and_refuses_missing_timestamps() {
        let text = "-1024,_D\n0,K_\n2048,__\n1024,__\n\n";
        assert_eq!(parse_packet_list(text), Some(vec![0, 2048, 1024]));
        assert_eq!(parse_packet_list("0,K_\nN/A,__\n"), None);
        assert_eq!(parse_packet_list(""), Some(vec![]));
    }

    #[test]
    fn json_packet_list_gives_the_same_times() {
        let tb = TimeBase { num: 1, den: 1024 };
        let packets: serde_json::Value = serde_json::json!([
            {"pts": -1024, "flags": "_D"},
            {"pts": 0, "flags": "K_"},
            {"pts": 2048, "flags": "__"},
            {"pts": 1024, "flags": "__"},
        ]);
        let packets = packets.as_array().unwrap();
        assert_eq!(packet_times(packets, tb), Some(vec![0.0, 1.0, 2.0]));
        // A kept packet without a timestamp: no list (the frame rate stands in).
        let missing = serde_json::json!([{"pts": 0, "flags": "K_"}, {"flags": "__"}]);
        assert_eq!(packet_times(missing.as_array().unwrap(), tb), None);
        assert_eq!(packet_times(&[], tb), None);
    }

    #[test]
    fn the_probed_release_chooses_the_passthrough_option() {
        assert_eq!(passthrough_option(Some((4, 4))), "-vsync");
        assert_eq!(passthrough_option(Some((5, 1))), "-fps_mode");
        assert_eq!(passthrough_option(Some((7, 0))), "-fps_mode");
    }
}
