//! Detector networks per call, single thread, including anchor decoding: short range
//! (`face_detection_short_range.tflite`, 128×128) and full range
//! (`face_detection_full_range_sparse.tflite`, 192×192, skipped when its file is absent); and the
//! whole detect() (letter-box + NMS) on a 512×512 frame, and the full range on a 1280×720 frame,
//! whole and in 640-px tiles. MediaPipe publishes ~ 0.6–1 ms per call for BlazeFace short range on
//! a desktop CPU (XNNPACK).

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

    let mut full = match FaceDetector::load_full_range_if_present(&dir) {
        Ok(Some(d)) => d,
        Ok(None) => {
            println!("SKIPPED full range: no face_detection_full_range_sparse.tflite in {dir:?}");
            return;
        }
        Err(e) => {
            println!("SKIPPED full range: {e}");
            return;
        }
    };
    let input: Vec<u8> = (0..192 * 192 * 3)
        .map(|i| ((i * 7919) % 256) as u8)
        .collect();
    c.bench_function("full_range_network_192", |b| {
        b.iter(|| std::hint::black_box(full.run_rgb8(&input).map(|v| v.len())))
    });
    let frame = image::RgbImage::from_fn(1280, 720, |x, y| {
        image::Rgb([(x % 256) as u8, (y % 256) as u8, ((x + y) % 256) as u8])
    });
    c.bench_function("full_range_detect_1280x720", |b| {
        b.iter(|| std::hint::black_box(full.detect(&frame).map(|v| v.len())))
    });
    c.bench_function("full_range_detect_tiled_640_1280x720", |b| {
        b.iter(|| std::hint::black_box(full.detect_tiled(&frame, 640).map(|v| v.len())))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
