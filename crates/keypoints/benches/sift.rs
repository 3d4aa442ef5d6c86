//! SIFT on a 720 × 1280 video frame (whole image, OpenCV's defaults) and on a face-sized crop
//! without upsampling (the per-frame variant), single thread; and matching 1000 × 1000
//! descriptors. The frame is `../shared`'s reference frame when present, else a synthetic
//! texture of the same size. `scripts/dev/compare_sift.sh` times OpenCV on the same frame.

use criterion::{criterion_group, criterion_main, Criterion};
use visage_keypoints::{match_descriptors, GrayImage, MatchOptions, Sift, SiftOptions};

/// The reference frame, or a synthetic texture of its size.
fn frame() -> GrayImage {
    let path = visage_testdata::shared_dir().join("reference/facemesh/d13_f150/frame.png");
    if let Ok(img) = image::open(&path) {
        let rgb = img.to_rgb8();
        let (w, h) = (rgb.width() as usize, rgb.height() as usize);
        if let Some(g) = GrayImage::from_rgb8(w, h, rgb.as_raw()) {
            return g;
        }
    }
    println!("{} missing: a synthetic frame instead", path.display());
    let (w, h) = (720, 1280);
    let data = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x as f32, y as f32)))
        .map(|(x, y)| {
            128.0
                + 50.0 * (0.07 * x + 0.03 * y).sin() * (0.05 * y - 0.02 * x).cos()
                + 30.0 * (0.013 * x * y / 40.0).sin()
        })
        .collect();
    GrayImage::from_vec(w, h, data).unwrap_or_default()
}

fn bench(c: &mut Criterion) {
    let image = frame();
    let mut sift = Sift::new(SiftOptions::default());
    let features = sift.detect_and_compute(&image);
    println!(
        "{}×{}: {} keypoints",
        image.width(),
        image.height(),
        features.len()
    );
    let mut group = c.benchmark_group("sift");
    group.sample_size(20);
    group.bench_function("frame_720x1280", |b| {
        b.iter(|| std::hint::black_box(sift.detect_and_compute(&image)))
    });
    // A face in a 720 × 1280 portrait clip spans ~300 px: the crop around it, with and
    // without the doubled octave, and at the pipeline's working size (`visage run
    // --keypoints` averages face crops down to at most 200 px wide, no doubling).
    let crop = image.crop(210, 330, 300, 360);
    let small = image.crop(260, 390, 200, 240);
    let mut face = Sift::new(SiftOptions {
        upsample: false,
        ..SiftOptions::default()
    });
    println!(
        "face crop 300×360: {} keypoints; 200×240: {}",
        face.detect_and_compute(&crop).len(),
        face.detect_and_compute(&small).len()
    );
    group.bench_function("face_crop_300x360_no_upsample", |b| {
        b.iter(|| std::hint::black_box(face.detect_and_compute(&crop)))
    });
    group.bench_function("face_crop_200x240_no_upsample", |b| {
        b.iter(|| std::hint::black_box(face.detect_and_compute(&small)))
    });
    let mut face_up = Sift::new(SiftOptions::default());
    group.bench_function("face_crop_300x360", |b| {
        b.iter(|| std::hint::black_box(face_up.detect_and_compute(&crop)))
    });
    group.finish();

    let n = features.len().min(1000);
    let (a, b) = (&features.descriptors[..n], &features.descriptors[..n]);
    c.bench_function("match_descriptors_self", |bench| {
        bench.iter(|| std::hint::black_box(match_descriptors(a, b, &MatchOptions::default())))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
