//! Iris network (`iris_landmark.tflite`, 64×64) per call, and the eye stage per face (both eyes:
//! crop, two network runs, mapping back), single thread. Without the model files it prints
//! SKIPPED.

use criterion::{criterion_group, criterion_main, Criterion};
use image::RgbImage;
use visage_face::{Eye, IrisLandmarker, IrisNetwork};

fn bench(c: &mut Criterion) {
    let dir = std::env::var_os("VISAGE_MODELS")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models")
        });
    let mut net = match IrisNetwork::load(&dir) {
        Ok(n) => n,
        Err(e) => {
            println!("SKIPPED: {e}");
            return;
        }
    };
    for (i, v) in net.input_mut().iter_mut().enumerate() {
        *v = ((i * 7919) % 256) as f32 / 255.0;
    }
    c.bench_function("iris_network_64", |b| {
        b.iter(|| std::hint::black_box(net.run()))
    });

    // A 640×480 frame and a face whose eye corners are 40 px apart (crops of 92 px).
    let frame = RgbImage::from_fn(640, 480, |x, y| {
        image::Rgb([
            (x * 7 % 256) as u8,
            (y * 5 % 256) as u8,
            ((x + y) % 256) as u8,
        ])
    });
    let mut points = vec![[0.0f32; 3]; 468];
    for (eye, x) in [(Eye::Right, 260.0), (Eye::Left, 340.0)] {
        let [a, b] = eye.corners();
        points[a] = [x - 20.0, 200.0, 0.0];
        points[b] = [x + 20.0, 202.0, 0.0];
    }
    let mut iris = IrisLandmarker::new(net);
    c.bench_function("iris_eyes_per_face", |b| {
        b.iter(|| std::hint::black_box(iris.eyes(&frame, &points).unwrap()))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
