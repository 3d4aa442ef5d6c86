//! Marks the tests that need `../shared` as ignored when it is absent; see `visage-testdata`.
fn main() {
    visage_testdata::emit_cfgs();
}
