//! The `rigid_transform_json` target: [`visage_fuzz_targets::rigid_transform_json`] (what it reads and checks is documented
//! there and in fuzz/README.md).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| visage_fuzz_targets::rigid_transform_json(data));
