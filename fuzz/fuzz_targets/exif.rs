//! `visage_video::focal_length_35mm_in`, the EXIF (TIFF) reader behind `focal_length_35mm`: any
//! bytes give a positive focal length or nothing, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use visage_video::focal_length_35mm_in;

fuzz_target!(|data: &[u8]| {
    if let Some(mm) = focal_length_35mm_in(data) {
        assert!(mm.is_finite() && mm > 0.0, "focal length {mm}");
    }
});
