//! `parse_tum_list`, the reader of a TUM RGB-D recording's `rgb.txt` / `depth.txt`: any text
//! gives timestamped file names in time order (every timestamp finite) or an error that names
//! the file, never a panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use visage_depth::parse_tum_list;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match parse_tum_list(text, Path::new("rgb.txt"), Path::new("rec")) {
        Ok(list) => {
            assert!(list
                .iter()
                .all(|(t, p)| t.is_some_and(f64::is_finite) && p.starts_with("rec")));
            assert!(list.windows(2).all(|w| w[0].0 <= w[1].0));
        }
        Err(e) => assert!(e.to_string().contains("rgb.txt")),
    }
});
