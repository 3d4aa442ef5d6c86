//! Turns on the crate-level example as a doctest when the model files, `../shared` and FFmpeg
//! are present (otherwise it is listed as ignored); see `visage-testdata`.
fn main() {
    visage_testdata::emit_cfgs();
}
