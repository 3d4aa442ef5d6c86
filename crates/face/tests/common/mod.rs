//! Helpers shared by the integration tests: locate `../shared` and the model directory, skip
//! visibly when either is absent.
#![allow(dead_code)]

use std::path::PathBuf;

/// `shared/reference/facemesh`, or `None` (after printing SKIPPED) when absent.
pub fn reference_dir() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/reference/facemesh");
    if dir.join("index.json").is_file() {
        Some(dir)
    } else {
        println!("SKIPPED: {} not found", dir.display());
        None
    }
}

/// `shared/data`, or `None` (after printing SKIPPED) when absent.
pub fn data_dir() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    if dir.is_dir() {
        Some(dir)
    } else {
        println!("SKIPPED: {} not found", dir.display());
        None
    }
}

/// The model directory (`$VISAGE_MODELS`, else the workspace's `models/`), or `None` (after
/// printing SKIPPED) when the pinned files are not there.
pub fn models_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("VISAGE_MODELS")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models"));
    if visage_face::model_files::models_present(&dir) {
        Some(dir)
    } else {
        println!(
            "SKIPPED: models not in {} (run `visage models fetch`)",
            dir.display()
        );
        None
    }
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
