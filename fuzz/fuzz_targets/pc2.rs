//! `visage_mesh::io::parse_pc2` (what `read_pc2` reads a point cache with): any bytes give a
//! cache whose every sample can be taken, or an error, never a panic or huge allocation.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use visage_mesh::io::parse_pc2;

fuzz_target!(|data: &[u8]| {
    match parse_pc2(data, Path::new("fuzz.pc2")) {
        Ok(cache) => {
            for k in 0..cache.samples() {
                assert_eq!(cache.sample(k).len(), 3 * cache.points);
            }
        }
        Err(e) => drop(e.to_string()),
    }
});
