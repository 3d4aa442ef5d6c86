//! `NetworkConfig::parse`, the reader of a depth network's JSON description: any text gives a
//! description whose values pass its own checks, or an error that names the file, never a
//! panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use visage_depth::NetworkConfig;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match NetworkConfig::parse(text, Path::new("net.json")) {
        Ok(c) => assert!(c.validate().is_ok()),
        Err(e) => assert!(e.to_string().contains("net.json")),
    }
});
