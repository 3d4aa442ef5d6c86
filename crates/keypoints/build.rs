//! Sets the `shared_data`, `model_files`, `ffmpeg` cfgs: tests needing an absent input are ignored.
fn main() {
    visage_testdata::emit_cfgs();
}
