//! Depth networks per frame, single thread: the region resampled into the input, the
//! inference, and the alignment to a reference face. The test network
//! (`tests/data/inverse_depth.onnx`, 64×64) always; a 256×256 U-Net of realistic size (7.8 M
//! parameters, `tests/data/make_networks.py --unet`) when `VISAGE_UNET` names it
//! (`scripts/dev/bench_depth_networks.sh` makes it and runs this).

use std::path::{Path, PathBuf};

use criterion::{criterion_group, criterion_main, Criterion};
use image::{Rgb, RgbImage};
use visage_camera::{DepthKind, DepthMap};
use visage_depth::{align, AlignMode, AlignmentOptions, DepthNetwork, OutputKind};

/// A 1280×720 frame with texture, and a face box in it.
fn frame() -> (RgbImage, [f32; 4]) {
    let image = RgbImage::from_fn(1280, 720, |x, y| {
        Rgb([
            (x * 3 % 256) as u8,
            ((x + y) % 256) as u8,
            ((x * y / 7) % 256) as u8,
        ])
    });
    (image, [520.0, 220.0, 240.0, 300.0])
}

/// A reference depth: a sphere-like bump over the face box, 0.6 m away.
fn reference(face: [f32; 4]) -> DepthMap {
    let mut d = DepthMap::empty(1280, 720, DepthKind::Z);
    let [x, y, w, h] = face;
    let (cx, cy) = (x + w / 2.0, y + h / 2.0);
    for v in y as u32..(y + h) as u32 {
        for u in x as u32..(x + w) as u32 {
            let r2 = ((u as f32 - cx) / w).powi(2) + ((v as f32 - cy) / h).powi(2);
            d.data[(v * 1280 + u) as usize] = 0.6 + 0.1 * r2;
        }
    }
    d
}

fn bench_network(c: &mut Criterion, name: &str, path: &Path) {
    let mut net = match DepthNetwork::load(path, None) {
        Ok(n) => n,
        Err(e) => {
            println!("SKIPPED {name}: {e}");
            return;
        }
    };
    let (image, face) = frame();
    let region = net.region(1280, 720, Some(face));
    c.bench_function(&format!("{name}_predict_face_region"), |b| {
        b.iter(|| std::hint::black_box(net.predict(&image, region).unwrap()))
    });
    let prediction = net.predict(&image, region).unwrap();
    let reference = reference(face);
    c.bench_function(&format!("{name}_align_and_map"), |b| {
        b.iter(|| {
            let fit = align(
                &prediction,
                &reference,
                OutputKind::Inverse,
                1.0,
                AlignMode::Auto,
                &AlignmentOptions::default(),
            );
            let map =
                fit.map(|fit| prediction.depth_map(1280, 720, DepthKind::Z, 3.0, |x| fit.depth(x)));
            std::hint::black_box(map)
        })
    });
}

fn bench(c: &mut Criterion) {
    let test = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/inverse_depth.onnx");
    bench_network(c, "test_network_64", &test);
    match std::env::var_os("VISAGE_UNET") {
        Some(unet) => bench_network(c, "unet_256", Path::new(&unet)),
        None => println!("SKIPPED unet_256: set VISAGE_UNET to a U-Net made by make_networks.py"),
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
