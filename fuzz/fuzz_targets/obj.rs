//! The `obj` target: [`visage_fuzz_targets::obj`] (what it reads and checks is documented
//! there and in fuzz/README.md).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| visage_fuzz_targets::obj(data));
