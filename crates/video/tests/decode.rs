//! Decoding tests. Those that decode need `ffmpeg`/`ffprobe` and are ignored without them.

use std::path::{Path, PathBuf};
use std::process::Command;

use visage_video::{probe, FrameSource, VideoError};

/// Writes a 2-second 64×48 test pattern at 10 fps (20 frames).
fn test_video(dir: &Path) -> PathBuf {
    let path = dir.join("pattern.mp4");
    let status = Command::new("ffmpeg")
        .args([
            "-v",
            "error",
            "-y",
            "-f",
            "lavfi",
            "-i",
            "testsrc=size=64x48:rate=10:duration=2",
            "-pix_fmt",
            "yuv420p",
            "-c:v",
            "libx264",
        ])
        .arg(&path)
        .status()
        .unwrap();
    assert!(status.success());
    path
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
    assert_eq!(frames[0].image.dimensions(), (64, 48));
    // testsrc changes over time: consecutive frames differ.
    assert_ne!(frames[0].image, frames[10].image);
}

#[test]
#[cfg_attr(not(ffmpeg), ignore = "needs FFmpeg")]
fn truncated_video_yields_readable_frames_then_names_the_break() {
    let dir = tempfile::tempdir().unwrap();
    // 50 frames, index up front (faststart), short GOPs: half the file holds whole frames.
    let path = dir.path().join("long.mp4");
    let status = Command::new("ffmpeg")
        .args([
            "-v",
            "error",
            "-y",
            "-f",
            "lavfi",
            "-i",
            "testsrc=size=64x48:rate=10:duration=5",
        ])
        .args([
            "-pix_fmt",
            "yuv420p",
            "-c:v",
            "libx264",
            "-bf",
            "0",
            "-g",
            "5",
            "-movflags",
            "+faststart",
        ])
        .arg(&path)
        .status()
        .unwrap();
    assert!(status.success());
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
