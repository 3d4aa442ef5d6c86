//! Helpers shared by the integration tests: locate `../shared` and the model directory. The
//! tests that need them are ignored when they are absent (see `visage-testdata`); these helpers
//! panic with a clear message if such a test runs anyway (under `CI=true`).
#![allow(dead_code)]

use std::path::PathBuf;

use visage_testdata::require;

/// `shared/reference/facemesh`.
#[track_caller]
pub fn reference_dir() -> PathBuf {
    let dir = require(visage_testdata::shared_dir().join("reference/facemesh"));
    require(dir.join("index.json"));
    dir
}

/// `shared/data`.
#[track_caller]
pub fn data_dir() -> PathBuf {
    require(visage_testdata::shared_dir().join("data"))
}

/// The model directory (`$VISAGE_MODELS`, else the workspace's `models/`), holding the pinned
/// files.
#[track_caller]
pub fn models_dir() -> PathBuf {
    let dir = visage_testdata::models_dir();
    for file in visage_testdata::MODEL_FILES {
        require(dir.join(file));
    }
    dir
}

/// The reference cases listed in `index.json`.
pub fn cases(reference: &std::path::Path) -> Vec<String> {
    let text = std::fs::read_to_string(reference.join("index.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v.as_array()
        .unwrap()
        .iter()
        .map(|c| c["case"].as_str().unwrap().to_owned())
        .collect()
}

pub fn read_json(path: PathBuf) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap()
}

pub fn read_rgb(path: PathBuf) -> image::RgbImage {
    image::open(&path).unwrap().to_rgb8()
}
