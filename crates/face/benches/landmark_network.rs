//! Landmark network (`face_landmark.tflite`, 192×192) per call, single thread.
//! MediaPipe publishes ~ 2–5 ms per call on a desktop CPU with XNNPACK (model card "FaceMesh").

use criterion::{criterion_group, criterion_main, Criterion};
use visage_face::LandmarkNetwork;

fn bench(c: &mut Criterion) {
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
