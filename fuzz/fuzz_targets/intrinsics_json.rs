//! The `intrinsics_json` target: [`visage_fuzz_targets::intrinsics_json`] (what it reads and checks is documented
//! there and in fuzz/README.md).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| visage_fuzz_targets::intrinsics_json(data));
