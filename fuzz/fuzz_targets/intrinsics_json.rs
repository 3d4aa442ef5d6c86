//! `Intrinsics::parse_json` (what `Intrinsics::load_json` reads an intrinsics file with): any
//! text gives validated intrinsics or an error, never a panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use visage_camera::Intrinsics;

fuzz_target!(|data: &[u8]| {
    // `load_json` reads the file as UTF-8 text; other bytes are an I/O error before parsing.
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match Intrinsics::parse_json(text, Path::new("fuzz.json")) {
        Ok(k) => assert!(k.validate().is_ok(), "accepted invalid intrinsics {k:?}"),
        Err(e) => drop(e.to_string()),
    }
});
