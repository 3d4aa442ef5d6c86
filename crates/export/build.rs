//! Embeds the report's 3-D viewer (`web/viewer/dist/viewer.js`, made by `web/viewer/build.sh`)
//! when it was built before visage: the `viewer_bundle` cfg.
fn main() {
    let bundle =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web/viewer/dist/viewer.js");
    println!("cargo::rerun-if-changed={}", bundle.display());
    println!("cargo::rustc-check-cfg=cfg(viewer_bundle)");
    if bundle.is_file() {
        println!("cargo::rustc-cfg=viewer_bundle");
    }
}
