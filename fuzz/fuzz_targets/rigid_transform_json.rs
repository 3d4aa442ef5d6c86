//! `RigidTransform::parse_json` (what `RigidTransform::load_json` reads a pose file with): any
//! text gives a validated rigid motion or an error, never a panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use visage_camera::RigidTransform;

fuzz_target!(|data: &[u8]| {
    // `load_json` reads the file as UTF-8 text; other bytes are an I/O error before parsing.
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match RigidTransform::parse_json(text, Path::new("pose.json")) {
        Ok(t) => assert!(t.validate().is_ok(), "accepted an invalid transform {t:?}"),
        Err(e) => drop(e.to_string()),
    }
});
