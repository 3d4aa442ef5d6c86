//! `visage_camera::parse_depth_png` (what `read_depth_png` reads a depth PNG with): any bytes
//! give a depth map of `width × height` values or an error, never a panic, hang or huge
//! allocation.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use visage_camera::{parse_depth_png, DepthKind};

fuzz_target!(|data: &[u8]| {
    match parse_depth_png(data, Path::new("fuzz.png"), 1000.0, DepthKind::Z) {
        Ok(depth) => assert_eq!(
            depth.data.len() as u64,
            depth.width as u64 * depth.height as u64
        ),
        Err(e) => drop(e.to_string()),
    }
});
