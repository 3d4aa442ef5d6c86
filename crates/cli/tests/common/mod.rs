//! Helpers shared by the CLI tests: run the real `visage` binary.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

/// Runs `visage ARGS…` and returns its output.
pub fn visage(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_visage"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs `visage ARGS…` and fails the test (with its stderr) unless it succeeds.
pub fn run_ok(args: &[&str]) {
    let o = visage(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A path as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The model folder and the 480×480 sample clip (the tests using them are ignored without them
/// or without FFmpeg).
#[track_caller]
pub fn inputs() -> (PathBuf, PathBuf) {
    let models = visage_testdata::models_dir();
    for file in visage_testdata::MODEL_FILES {
        visage_testdata::require(models.join(file));
    }
    let clip =
        visage_testdata::require(visage_testdata::shared_dir().join("data/video/lp_d18.mp4"));
    (models, clip)
}

/// A JSON file's contents.
pub fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Starts `visage ARGS…` and returns it once `marker` exists (failing after two minutes).
pub fn spawn_until(args: &[&str], marker: &Path, stderr: Stdio) -> Child {
    let child = Command::new(env!("CARGO_BIN_EXE_visage"))
        .args(args)
        .stderr(stderr)
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while !marker.exists() {
        assert!(
            started.elapsed().as_secs() < 120,
            "no {marker:?} after two minutes"
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    child
}

/// The first 24 frames of `clip` re-encoded with the index up front (faststart) and cut in the
/// middle of the data, as `DIR/cut.mp4`: a video that breaks part-way (needs FFmpeg).
pub fn truncated_clip(dir: &Path, clip: &Path) -> PathBuf {
    let full = dir.join("full.mp4");
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i", s(clip), "-frames:v", "24", "-an"])
        .args([
            "-c:v",
            "libx264",
            "-g",
            "4",
            "-bf",
            "0",
            "-movflags",
            "+faststart",
        ])
        .arg(&full)
        .status()
        .unwrap();
    assert!(status.success());
    let bytes = std::fs::read(&full).unwrap();
    let cut = dir.join("cut.mp4");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    cut
}
