//! Test support: where the shared data (`../shared` beside the checkout: clips, reference
//! outputs, ICT-FaceKit) and the MediaPipe model files are, and the switches that make a test
//! needing them *ignored* — visible as such in the test summary — when they are absent.
//!
//! A crate whose tests need them has a two-line build script,
//! `fn main() { visage_testdata::emit_cfgs(); }`, and marks each such test:
//!
//! ```text
//! #[test]
//! #[cfg_attr(not(shared_data), ignore = "needs ../shared beside the checkout")]
//! fn parity() { let dir = visage_testdata::shared_dir(); … }
//! ```
//!
//! The switches are `shared_data`, `model_files`, `ffmpeg` and `web_tools` (the glTF validator,
//! the report viewer's bundle and Chromium: `web/viewer/build.sh`). Under `CI=true` all are
//! on whatever is present, so a missing input fails its tests instead of skipping them (CI
//! always has them). The build script re-runs when `CI`, `VISAGE_MODELS` or
//! `VISAGE_TEST_DATA` change; `scripts/test.sh` sets the last to what is present, so fetching
//! the models or adding `../shared` turns the tests on.

#![forbid(unsafe_code)]

use std::path::{Path, PathBuf};

/// The model files the tests use (`visage models fetch`).
pub const MODEL_FILES: [&str; 6] = [
    "face_detection_short_range.tflite",
    "face_landmark.tflite",
    "geometry_pipeline_metadata_landmarks.binarypb",
    "iris_landmark.tflite",
    "face_detection_full_range_sparse.tflite",
    "face_landmark_with_attention.tflite",
];

/// The workspace root (the folder with the top-level `Cargo.toml`).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `../shared` beside the checkout.
pub fn shared_dir() -> PathBuf {
    workspace_root().join("../shared")
}

/// The model folder: `$VISAGE_MODELS`, else `models/` in the workspace.
pub fn models_dir() -> PathBuf {
    std::env::var_os("VISAGE_MODELS")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join("models"))
}

/// Whether `../shared` holds the data and reference outputs.
pub fn has_shared_data() -> bool {
    let shared = shared_dir();
    shared.join("data").is_dir() && shared.join("reference").is_dir()
}

/// Whether the model folder holds [`MODEL_FILES`].
pub fn has_model_files() -> bool {
    let dir = models_dir();
    MODEL_FILES.iter().all(|f| dir.join(f).is_file())
}

/// Whether FFmpeg's command-line tools run.
pub fn has_ffmpeg() -> bool {
    ["ffmpeg", "ffprobe"].iter().all(|tool| {
        std::process::Command::new(tool)
            .arg("-version")
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

/// The browser-side tools (`web/viewer`): its node modules, its bundle and Debian's Chromium.
pub fn web_dir() -> PathBuf {
    workspace_root().join("web/viewer")
}

/// Whether `web/viewer` is built (`web/viewer/build.sh`) and Chromium is installed — what the
/// glTF validator and the report's browser test need.
pub fn has_web_tools() -> bool {
    let web = web_dir();
    web.join("node_modules/gltf-validator").is_dir()
        && web.join("dist/viewer.js").is_file()
        && Path::new(CHROMIUM).is_file()
}

/// The browser the report's test drives.
pub const CHROMIUM: &str = "/usr/bin/chromium";

/// For build scripts: declares the switches and turns on those whose input is present (all of
/// them under `CI=true`).
pub fn emit_cfgs() {
    for var in ["CI", "VISAGE_MODELS", "VISAGE_TEST_DATA"] {
        println!("cargo::rerun-if-env-changed={var}");
    }
    println!("cargo::rerun-if-changed=build.rs");
    println!(
        "cargo::rerun-if-changed={}",
        web_dir().join("dist/viewer.js").display()
    );
    let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
    let switches = [
        ("shared_data", has_shared_data()),
        ("model_files", has_model_files()),
        ("ffmpeg", has_ffmpeg()),
        ("web_tools", has_web_tools()),
    ];
    for (name, present) in switches {
        println!("cargo::rustc-check-cfg=cfg({name})");
        if present || ci {
            println!("cargo::rustc-cfg={name}");
        }
    }
}

/// `path`, or a panic that says what is missing and how to get it — the first line of a test
/// that runs because CI forced it on.
#[track_caller]
pub fn require(path: PathBuf) -> PathBuf {
    assert!(
        path.exists(),
        "{} is missing: the shared data belongs at ../shared beside the checkout; the models \
         come from `scripts/setup.sh` (or `visage models fetch`)",
        path.display()
    );
    path
}

/// `jpeg` (a JPEG file's bytes) with an EXIF block whose only tag is the orientation
/// (0x0112; 1 upright, 6 stored turned so that showing it needs a quarter turn clockwise, …),
/// inserted after the start-of-image marker: what a phone writes for a portrait photo.
pub fn with_exif_orientation(jpeg: &[u8], orientation: u16) -> Vec<u8> {
    // "Exif\0\0", a little-endian TIFF header, IFD0 with one entry (tag 0x0112, SHORT,
    // count 1, the value) and no next IFD.
    let mut app1 = b"Exif\0\0II*\0\x08\0\0\0\x01\0\x12\x01\x03\0\x01\0\0\0".to_vec();
    app1.extend_from_slice(&orientation.to_le_bytes());
    app1.extend_from_slice(&[0; 6]);
    let mut out = jpeg[..2].to_vec();
    out.extend_from_slice(&[0xFF, 0xE1]);
    out.extend_from_slice(&((app1.len() + 2) as u16).to_be_bytes());
    out.extend_from_slice(&app1);
    out.extend_from_slice(&jpeg[2..]);
    out
}
