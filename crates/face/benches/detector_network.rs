//! Detector network (`face_detection_short_range.tflite`, 128×128) per call, single thread,
//! including anchor decoding; and the whole detect() on a 512×512 frame (letter-box + NMS).
//! MediaPipe publishes ~ 0.6–1 ms per call for BlazeFace short range on a desktop CPU (XNNPACK).

use criterion::{criterion_group, criterion_main, Criterion};
use visage_face::FaceDetector;

fn bench(c: &mut Criterion) {
    let dir = std::env::var_os("VISAGE_MODELS")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models")
        });
    let mut det = match FaceDetector::load(&dir) {
        Ok(d) => d,
        Err(e) => {
            println!("SKIPPED: {e}");
            return;
        }
    };
    let input: Vec<u8> = (0..128 * 128 * 3)
        .map(|i| ((i * 7919) % 256) as u8)
        .collect();
    c.bench_function("detector_network_128", |b| {
        b.iter(|| std::hint::black_box(det.run_rgb8(&input).map(|v| v.len())))
    });
    let frame = image::RgbImage::from_fn(512, 512, |x, y| {
        image::Rgb([(x % 256) as u8, (y % 256) as u8, ((x + y) % 256) as u8])
    });
    c.bench_function("detect_frame_512", |b| {
        b.iter(|| std::hint::black_box(det.detect(&frame).map(|v| v.len())))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
