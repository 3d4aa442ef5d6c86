//! Landmark network (`face_landmark.tflite`, 192×192) per call, single thread, and the rotated
//! face crop that fills its input.
//! MediaPipe publishes ~ 2–5 ms per call on a desktop CPU with XNNPACK (model card "FaceMesh").

use criterion::{criterion_group, criterion_main, Criterion};
use visage_face::{LandmarkNetwork, Roi};

fn bench(c: &mut Criterion) {
    // A 480×480 frame and a rotated face box inside it, as the tracker gives.
    let frame = image::RgbImage::from_fn(480, 480, |x, y| {
        image::Rgb([
            (x * 7 % 256) as u8,
            (y * 5 % 256) as u8,
            ((x + y) % 256) as u8,
        ])
    });
    let roi = Roi {
        center: [241.3, 226.8],
        size: 301.5,
        rotation: 0.12,
    };
    let mut crop = vec![0.0; 192 * 192 * 3];
    c.bench_function("crop_roi_192", |b| {
        b.iter(|| visage_face::crop::crop_roi(&frame, std::hint::black_box(&roi), 192, &mut crop))
    });
    let dir = std::env::var_os("VISAGE_MODELS")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models")
        });
    let mut net = match LandmarkNetwork::load(&dir) {
        Ok(n) => n,
        Err(e) => {
            println!("SKIPPED: {e}");
            return;
        }
    };
    for (i, v) in net.input_mut().iter_mut().enumerate() {
        *v = ((i * 7919) % 256) as f32 / 255.0;
    }
    c.bench_function("landmark_network_192", |b| {
        b.iter(|| std::hint::black_box(net.run()))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
