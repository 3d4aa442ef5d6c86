//! `KeypointsFile::parse_json` (what `visage match` reads a keypoints file with): any text gives
//! keypoints with one 128-byte descriptor each, or an error, never a panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use visage_keypoints::KeypointsFile;

fuzz_target!(|data: &[u8]| {
    // The file is read as UTF-8 text; other bytes are an I/O error before parsing.
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match KeypointsFile::parse_json(text, Path::new("fuzz.json")) {
        Ok(f) => assert_eq!(f.keypoints.len(), f.descriptors.len()),
        Err(e) => drop(e.to_string()),
    }
});
