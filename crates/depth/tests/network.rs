//! The depth network runtime on real ONNX files (`tests/data/make_networks.py` writes them):
//! a known depth from a known image, and a clear error for each file that is not a usable
//! depth network.

use std::path::{Path, PathBuf};

use image::{Rgb, RgbImage};
use visage_camera::DepthKind;
use visage_depth::{align, AlignMode, AlignmentOptions, DepthNetwork, FrameRegion, OutputKind};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// A 64×64 image whose red channel is constant over 2×2 blocks (`red(i, j)` for block
/// (i, j)), green and blue arbitrary.
fn block_image(red: impl Fn(u32, u32) -> u8) -> RgbImage {
    RgbImage::from_fn(64, 64, |x, y| {
        Rgb([
            red(x / 2, y / 2),
            ((x * 7 + y) % 256) as u8,
            ((x * y) % 256) as u8,
        ])
    })
}

#[test]
fn the_test_network_gives_the_depth_its_generator_promises() {
    let mut net = DepthNetwork::load(&data("inverse_depth.onnx"), None).unwrap();
    assert_eq!(net.input_size(), (64, 64));
    assert_eq!(net.output_size(), (32, 32));
    assert_eq!(net.config().output.kind, OutputKind::Inverse);
    let red = |i: u32, j: u32| ((i * 5 + j * 3) % 256) as u8;
    let image = block_image(red);
    let p = net.predict(&image, FrameRegion::frame(64, 64)).unwrap();
    let mut worst = 0.0f32;
    for j in 0..32 {
        for i in 0..32 {
            let expected = 0.2 + 0.6 * red(i, j) as f32 / 255.0;
            worst = worst.max((p.values[(j * 32 + i) as usize] - expected).abs());
        }
    }
    assert!(worst < 1e-5, "largest difference {worst}");
}

#[test]
fn a_frame_region_is_resampled_into_the_input_and_back() {
    // A 128×96 frame, uniform colour: the network sees it through a face region that reaches
    // outside the frame (edge pixels repeated) and gives one value everywhere.
    let image = RgbImage::from_pixel(128, 96, Rgb([51, 10, 200]));
    let mut net = DepthNetwork::load(&data("inverse_depth.onnx"), None).unwrap();
    let region = net.region(128, 96, Some([80.0, 40.0, 40.0, 50.0]));
    assert!(region.left + region.width > 128.0, "{region:?}");
    let p = net.predict(&image, region).unwrap();
    let expected = 0.2f32 + 0.6 * 0.2;
    assert!(p.values.iter().all(|v| (v - expected).abs() < 1e-5));
    // As a depth map of the frame: inverse depth 1 / value where the region covers it.
    let map = p.depth_map(128, 96, DepthKind::Z, 10.0, |x| 1.0 / x);
    assert!((map.at(100, 60) - 1.0 / expected).abs() < 1e-4);
    assert_eq!(map.at(2, 2), 0.0, "outside the region");
}

#[test]
fn an_image_that_encodes_inverse_depth_is_aligned_back_to_metres() {
    // The reference: a slanted plane 0.4–0.6 m away. The image encodes a relative inverse
    // depth in its red channel; the network reproduces it; the alignment finds the metres.
    let z = |i: u32| 0.4 + 0.2 * i as f64 / 31.0;
    let (a, b) = (0.05, 0.05); // red / 255 = a / z − b: in [0.033, 0.075].
    let red = |i: u32, _: u32| ((a / z(i) - b) * 255.0 * 4.0).round() as u8;
    let image = block_image(red);
    let mut net = DepthNetwork::load(&data("inverse_depth.onnx"), None).unwrap();
    let p = net.predict(&image, FrameRegion::frame(64, 64)).unwrap();
    let mut reference = visage_camera::DepthMap::empty(64, 64, DepthKind::Z);
    for v in 0..64 {
        for u in 0..64 {
            // The depth the quantised red value stands for.
            let r = red(u / 2, v / 2) as f64 / (255.0 * 4.0);
            reference.data[(v * 64 + u) as usize] = (a / (r + b)) as f32;
        }
    }
    let fit = align(
        &p,
        &reference,
        OutputKind::Inverse,
        1.0,
        AlignMode::Auto,
        &AlignmentOptions::default(),
    )
    .unwrap();
    assert!(fit.residual_m < 2e-3, "{fit:?}");
    let map = p.depth_map(64, 64, DepthKind::Z, 10.0, |x| fit.depth(x));
    let err = (map.at(40, 20) - reference.at(40, 20)).abs();
    assert!(err < 2e-3, "{err}");
}

/// The error loading `name` gives, as the user reads it.
fn load_error(name: &str) -> String {
    DepthNetwork::load(&data(name), None)
        .unwrap_err()
        .to_string()
}

#[test]
fn files_that_are_not_usable_depth_networks_are_refused_by_name() {
    let e = load_error("missing.onnx");
    assert!(
        e.contains("missing.onnx") && e.contains("No such file"),
        "{e}"
    );
    let e = load_error("make_networks.py");
    assert!(
        e.contains("make_networks.py") && e.contains("not an ONNX model"),
        "{e}"
    );
    let e = load_error("rank3_input.onnx");
    assert!(
        e.contains("rank3_input.onnx") && e.contains("rank 3"),
        "{e}"
    );
    let e = load_error("unsupported_op.onnx");
    assert!(
        e.contains("unsupported_op.onnx") && e.contains("MaxUnpool"),
        "{e}"
    );
    let e = load_error("wrong_output.onnx");
    assert!(
        e.contains("wrong_output.onnx") && e.contains("48×16") && e.contains("aspect ratio"),
        "{e}"
    );
}

#[test]
fn a_description_that_disagrees_with_the_model_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let net = dir.path().join("net.onnx");
    std::fs::copy(data("inverse_depth.onnx"), &net).unwrap();
    std::fs::write(dir.path().join("net.json"), r#"{"input": {"width": 128}}"#).unwrap();
    let e = DepthNetwork::load(&net, None).unwrap_err().to_string();
    assert!(
        e.contains("net.onnx") && e.contains("input.width = 128"),
        "{e}"
    );
    std::fs::write(dir.path().join("net.json"), r#"{"output": {"kind": 3}}"#).unwrap();
    let e = DepthNetwork::load(&net, None).unwrap_err().to_string();
    assert!(e.contains("net.json"), "{e}");
}
