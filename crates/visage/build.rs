//! Turns on the crate-level example as a doctest when the model files, `../shared` and FFmpeg
//! are present (otherwise it is listed as ignored); see `visage-testdata`. Embeds the live
//! page's script (`web/viewer/dist/live.js`, made by `web/viewer/build.sh`) when it was built
//! before visage: the `live_page_bundle` cfg.
fn main() {
    visage_testdata::emit_cfgs();
    let bundle =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web/viewer/dist/live.js");
    println!("cargo::rerun-if-changed={}", bundle.display());
    println!("cargo::rustc-check-cfg=cfg(live_page_bundle)");
    if bundle.is_file() {
        println!("cargo::rustc-cfg=live_page_bundle");
    }
}
