//! Decoding tests. Those that decode need `ffmpeg`/`ffprobe` and are ignored without them.

use std::path::{Path, PathBuf};
use std::process::Command;

use visage_video::{probe, FrameSource, VideoError};

/// Encodes FFmpeg's 64×48 test pattern at 10 fps for `seconds` into `dir/name` with H.264,
/// `extra` output options (filters, GOP, container flags) before the file name.
fn encode_pattern(dir: &Path, name: &str, seconds: u32, extra: &[&str]) -> PathBuf {
    let path = dir.join(name);
    let source = format!("testsrc=size=64x48:rate=10:duration={seconds}");
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-f", "lavfi", "-i", &source])
        .args(extra)
        .args(["-pix_fmt", "yuv420p", "-c:v", "libx264"])
        .arg(&path)
        .status()
        .unwrap();
    assert!(status.success());
    path
}

/// Writes a 2-second test pattern (20 frames).
fn test_video(dir: &Path) -> PathBuf {
    encode_pattern(dir, "pattern.mp4", 2, &[])
}

#[test]
#[cfg_attr(not(ffmpeg), ignore = "needs FFmpeg")]
fn decodes_every_frame_of_a_video() {
    let dir = tempfile::tempdir().unwrap();
    let path = test_video(dir.path());
    let info = probe(&path).unwrap();
    assert_eq!((info.width, info.height, info.rotation), (64, 48, 0));
    assert!((info.fps.unwrap() - 10.0).abs() < 1e-9);
    let frames: Vec<_> = FrameSource::open(&path)
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(frames.len(), 20);
    assert_eq!(frames[19].index, 19);
    for (i, f) in frames.iter().enumerate() {
        let t = f.timestamp_s.unwrap();
        assert!((t - i as f64 / 10.0).abs() < 1e-9, "frame {i} at {t} s");
    }
    assert_eq!(frames[0].image.dimensions(), (64, 48));
    // testsrc changes over time: consecutive frames differ.
    assert_ne!(frames[0].image, frames[10].image);
}

/// Frames handed back to the source's pool lend their buffers to later frames, which decode
/// to the same pixels as fresh ones (every byte of a reused buffer is read again).
#[test]
#[cfg_attr(not(ffmpeg), ignore = "needs FFmpeg")]
fn frames_decode_the_same_into_recycled_buffers() {
    let dir = tempfile::tempdir().unwrap();
    let path = test_video(dir.path());
    let fresh: Vec<_> = FrameSource::open(&path)
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    let mut source = FrameSource::open(&path).unwrap();
    let pool = source.frame_pool().expect("a video has a frame pool");
    let mut recycled = Vec::new();
    let mut reused = 0;
    for (i, frame) in source.by_ref().enumerate() {
        let frame = frame.unwrap();
        assert_eq!(frame.image, fresh[i].image, "frame {i}");
        let pointer = frame.image.as_raw().as_ptr();
        reused += usize::from(recycled.contains(&pointer));
        recycled.push(pointer);
        pool.recycle(frame);
    }
    assert_eq!(recycled.len(), fresh.len());
    assert_eq!(
        reused,
        fresh.len() - 1,
        "every frame after the first reuses a buffer"
    );
}

#[test]
#[cfg_attr(not(ffmpeg), ignore = "needs FFmpeg")]
fn truncated_video_yields_readable_frames_then_names_the_break() {
    let dir = tempfile::tempdir().unwrap();
    // 50 frames, index up front (faststart), short GOPs: half the file holds whole frames.
    let path = encode_pattern(
        dir.path(),
        "long.mp4",
        5,
        &["-bf", "0", "-g", "5", "-movflags", "+faststart"],
    );
    let bytes = std::fs::read(&path).unwrap();
    let cut = dir.path().join("cut.mp4");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let items: Vec<_> = FrameSource::open(&cut).unwrap().collect();
    let ok = items.iter().take_while(|r| r.is_ok()).count();
    assert!(ok > 0 && ok < 50, "{ok} frames decoded from half a file");
    assert_eq!(items.len(), ok + 1, "exactly one error, at the end");
    let Some(Err(e)) = items.last() else {
        panic!("no error reported for a truncated file")
    };
    let VideoError::Broken { frame, .. } = e else {
        panic!("unexpected error {e}")
    };
    assert_eq!(*frame, ok);
    assert!(e.to_string().contains("cut.mp4"), "{e}");
    // Garbage is not a video, and the error names the file.
    let junk = dir.path().join("junk.mp4");
    std::fs::write(&junk, b"definitely not a video").unwrap();
    let err = FrameSource::open(&junk).err().unwrap().to_string();
    assert!(err.contains("junk.mp4"), "{err}");
}

#[test]
#[cfg_attr(not(all(shared_data, ffmpeg)), ignore = "needs ../shared and FFmpeg")]
fn clips_of_the_project_decode_fully() {
    let path =
        visage_testdata::require(visage_testdata::shared_dir().join("data/video/lp_d18.mp4"));
    let info = probe(&path).unwrap();
    let mut n = 0;
    for f in FrameSource::open(&path).unwrap() {
        let f = f.unwrap();
        assert_eq!(f.image.dimensions(), (info.width, info.height));
        n += 1;
    }
    if let Some(count) = info.frame_count {
        assert_eq!(n, count);
    }
    assert!(n > 100);
}

/// A clip's frames: timestamps from 0, strictly increasing, spaced 1/fps (constant-rate
/// clips); a plausible frame rate; as many frames as the container states.
fn check_clip_timestamps(name: &str) {
    let path =
        visage_testdata::require(visage_testdata::shared_dir().join("data/video").join(name));
    let info = probe(&path).unwrap();
    let fps = info.fps.expect("a frame rate");
    assert!((10.0..=240.0).contains(&fps), "{name}: {fps} fps");
    let avg = info.avg_fps.expect("an average frame rate");
    assert!((avg - fps).abs() < 0.01 * fps, "{name}: {avg} vs {fps} fps");
    let source = FrameSource::open(&path).unwrap();
    assert_eq!(source.frame_rate(), Some(fps));
    let times: Vec<f64> = source
        .map(|f| f.unwrap().timestamp_s.expect("a timestamp"))
        .collect();
    if let Some(count) = info.frame_count {
        assert_eq!(times.len(), count, "{name}");
    }
    assert_eq!(times[0], 0.0, "{name}");
    for (i, w) in times.windows(2).enumerate() {
        let step = w[1] - w[0];
        assert!(step > 0.0, "{name}: frame {} not after frame {i}", i + 1);
        assert!(
            (step * fps - 1.0).abs() < 0.01,
            "{name}: frames {i}..{} {step} s apart at {fps} fps",
            i + 1
        );
    }
}

#[test]
#[cfg_attr(not(all(shared_data, ffmpeg)), ignore = "needs ../shared and FFmpeg")]
fn clips_have_increasing_timestamps_at_their_frame_rate() {
    check_clip_timestamps("lp_d18.mp4");
    check_clip_timestamps("lp_d13.mp4");
}

#[test]
#[cfg_attr(not(ffmpeg), ignore = "needs FFmpeg")]
fn variable_frame_rate_keeps_every_frame_at_its_own_time() {
    let dir = tempfile::tempdir().unwrap();
    // 20 frames of a 10 fps pattern, the later ones spread out (setpts). Matroska keeps
    // variable timestamps by default (MP4 would be made constant-rate without an option).
    let path = encode_pattern(
        dir.path(),
        "vfr.mkv",
        2,
        &["-vf", "setpts='if(lt(N,10),N/10,1+(N-10)/5)/TB'"],
    );
    // When ffprobe, decoding every frame, says each frame is shown.
    let out = Command::new("ffprobe")
        .args(["-v", "error", "-select_streams", "v:0", "-show_entries"])
        .args(["frame=best_effort_timestamp_time", "-of", "csv=p=0"])
        .arg(&path)
        .output()
        .unwrap();
    let expected: Vec<f64> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.split(',').next()?.trim().parse().ok())
        .collect();
    assert_eq!(expected.len(), 20);
    let steps: Vec<f64> = expected.windows(2).map(|w| w[1] - w[0]).collect();
    let (min, max) = steps
        .iter()
        .fold((f64::MAX, 0.0f64), |(a, b), &s| (a.min(s), b.max(s)));
    assert!(
        max > 1.5 * min,
        "not a variable frame rate: steps {steps:?}"
    );
    let frames: Vec<_> = FrameSource::open(&path)
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    // A constant-rate pipe would repeat frames to fill the longer gaps.
    assert_eq!(frames.len(), 20);
    for (f, want) in frames.iter().zip(&expected) {
        let t = f.timestamp_s.unwrap();
        assert!(
            (t - want).abs() < 1e-6,
            "frame {} at {t} s, not {want}",
            f.index
        );
    }
    // Consecutive frames are distinct pictures, none repeated.
    assert!(frames.windows(2).all(|w| w[0].image != w[1].image));
    assert_eq!(probe(&path).unwrap().fps, Some(10.0));
}

#[test]
fn folders_and_single_images() {
    let dir = tempfile::tempdir().unwrap();
    for (i, name) in ["b.png", "a.png", "notes.txt"].iter().enumerate() {
        let p = dir.path().join(name);
        if name.ends_with(".png") {
            image::RgbImage::from_pixel(4, 3, image::Rgb([i as u8, 0, 0]))
                .save(&p)
                .unwrap();
        } else {
            std::fs::write(&p, "x").unwrap();
        }
    }
    let frames: Vec<_> = FrameSource::open(dir.path())
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(frames.len(), 2);
    assert!(frames[0].source.ends_with("a.png") && frames[0].image.get_pixel(0, 0)[0] == 1);
    assert_eq!(frames[1].index, 1);
    // Images state no time; with a frame rate given, image i is at i / fps.
    assert!(frames.iter().all(|f| f.timestamp_s.is_none()));
    let source = FrameSource::open(dir.path()).unwrap();
    assert_eq!(source.frame_rate(), None);
    let source = source.with_frame_rate(25.0);
    assert_eq!(source.frame_rate(), Some(25.0));
    let times: Vec<_> = source.map(|f| f.unwrap().timestamp_s).collect();
    assert_eq!(times, [Some(0.0), Some(0.04)]);
    let one: Vec<_> = FrameSource::open(&dir.path().join("b.png"))
        .unwrap()
        .collect();
    assert_eq!(one.len(), 1);
    let bad = dir.path().join("bad.png");
    std::fs::write(&bad, b"\x89PNG broken").unwrap();
    let err = FrameSource::open(&bad)
        .unwrap()
        .next()
        .unwrap()
        .unwrap_err()
        .to_string();
    assert!(err.contains("bad.png"), "{err}");
    let empty = tempfile::tempdir().unwrap();
    assert!(matches!(
        FrameSource::open(empty.path()),
        Err(VideoError::EmptyFolder { .. })
    ));
}
