//! The detector on images whose answer is known: Gaussian blobs (position and scale), exact
//! 90° rotations (angles and descriptors), affine brightness changes (descriptors).

use visage_keypoints::{Descriptor, Features, GrayImage, Keypoint, Sift, SiftOptions};

/// A dark background with bright Gaussian blobs `(x, y, σ)`.
fn blobs(w: usize, h: usize, spots: &[(f32, f32, f32)]) -> GrayImage {
    let data = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x as f32, y as f32)))
        .map(|(x, y)| {
            let v: f32 = spots
                .iter()
                .map(|&(cx, cy, s)| {
                    let r2 = (x - cx).powi(2) + (y - cy).powi(2);
                    (-r2 / (2.0 * s * s)).exp()
                })
                .sum();
            20.0 + 200.0 * v
        })
        .collect();
    GrayImage::from_vec(w, h, data).unwrap()
}

/// A texture with structure at several scales (sums of products of sines, no symmetry).
fn texture(w: usize, h: usize) -> GrayImage {
    let data = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x as f32, y as f32)))
        .map(|(x, y)| {
            let a = (0.21 * x + 0.05 * y).sin() * (0.13 * y - 0.04 * x).cos();
            let b = (0.045 * x + 0.031 * y + 1.0).sin() * (0.052 * y).cos();
            let c = ((x - 70.0).powi(2) + (y - 50.0).powi(2)).sqrt() * 0.11;
            128.0 + 45.0 * a + 40.0 * b + 25.0 * c.sin()
        })
        .collect();
    GrayImage::from_vec(w, h, data).unwrap()
}

fn nearest(features: &Features, x: f32, y: f32) -> (usize, f32) {
    features
        .keypoints
        .iter()
        .enumerate()
        .map(|(i, k)| (i, (k.x - x).hypot(k.y - y)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((usize::MAX, f32::INFINITY))
}

fn distance(a: &Descriptor, b: &Descriptor) -> f32 {
    a.iter()
        .zip(b)
        .map(|(&x, &y)| (f32::from(x) - f32::from(y)).powi(2))
        .sum::<f32>()
        .sqrt()
}

#[test]
fn gaussian_blobs_are_found_at_their_centre_and_scale() {
    // Sub-pixel centres, scales across three octaves.
    let spots = [
        (40.3, 45.6, 2.5),
        (120.7, 50.2, 4.0),
        (60.4, 130.9, 6.5),
        (150.2, 150.5, 10.0),
    ];
    let image = blobs(220, 210, &spots);
    let features = Sift::new(SiftOptions::default()).detect_and_compute(&image);
    for &(x, y, s) in &spots {
        let (i, d) = nearest(&features, x, y);
        assert!(
            d < 0.25 * s.max(1.0),
            "blob at ({x}, {y}) σ {s}: nearest at {d} px"
        );
        let k = &features.keypoints[i];
        // size = 2σ of the scale-normalised DoG extremum; for a Gaussian blob of σ_b that is
        // σ_b (Lindeberg), give or take the DoG's approximation of the Laplacian.
        let sigma = k.size / 2.0;
        assert!(
            (sigma / s - 1.0).abs() < 0.2,
            "blob σ {s}: keypoint σ {sigma}"
        );
        assert!(k.response > 0.0);
    }
}

#[test]
fn a_quarter_turn_adds_ninety_degrees_and_keeps_the_descriptors() {
    let (w, h) = (180, 150);
    let image = texture(w, h);
    // Clockwise on screen: (x, y) → (h − 1 − y, x).
    let rotated: Vec<f32> = (0..w)
        .flat_map(|yr| (0..h).map(move |xr| (xr, yr)))
        .map(|(xr, yr)| image.at(yr, h - 1 - xr))
        .collect();
    let rotated = GrayImage::from_vec(h, w, rotated).unwrap();
    let mut sift = Sift::new(SiftOptions::default());
    let (a, b) = (
        sift.detect_and_compute(&image),
        sift.detect_and_compute(&rotated),
    );
    assert!(a.len() > 40, "{} keypoints", a.len());
    let mut checked = 0;
    let mut descriptor_distances = Vec::new();
    for (k, da) in a.keypoints.iter().zip(&a.descriptors) {
        let (xr, yr) = ((h - 1) as f32 - k.y, k.x);
        // The same point at the same scale with the angle turned by 90°.
        let same = b.keypoints.iter().zip(&b.descriptors).find(|(q, _)| {
            // Up to the upsampling's interpolation (see below).
            (q.x - xr).hypot(q.y - yr) < 0.5
                && (q.size - k.size).abs() < 0.05 * k.size
                && angle_gap(q.angle, k.angle + 90.0) < 5.0
        });
        if let Some((_, db)) = same {
            checked += 1;
            descriptor_distances.push(distance(da, db));
        }
    }
    assert!(
        checked as f32 > 0.8 * a.len() as f32,
        "{checked} of {} keypoints found turned",
        a.len()
    );
    descriptor_distances.sort_by(f32::total_cmp);
    let median = descriptor_distances[descriptor_distances.len() / 2];
    // Descriptors have norm 512. Upsampling samples the input a quarter pixel back along both
    // axes, which a quarter turn does not map onto itself: equal up to that interpolation
    // (measured median 30), against ~300 for unrelated keypoints.
    assert!(median < 0.1 * 512.0, "median descriptor distance {median}");
    let unrelated = distance(&a.descriptors[0], &a.descriptors[a.len() / 2]);
    assert!(
        unrelated > 4.0 * median,
        "unrelated descriptors {unrelated} apart"
    );
}

fn angle_gap(a: f32, b: f32) -> f32 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

#[test]
fn affine_brightness_keeps_keypoints_and_descriptors() {
    let image = texture(160, 140);
    let brighter = GrayImage::from_vec(
        160,
        140,
        image.data().iter().map(|v| 0.8 * v + 30.0).collect(),
    )
    .unwrap();
    let mut sift = Sift::new(SiftOptions::default());
    let (a, b) = (
        sift.detect_and_compute(&image),
        sift.detect_and_compute(&brighter),
    );
    // Lower contrast drops the weakest keypoints (the threshold is absolute); each survivor
    // sits where it was, with the same descriptor.
    assert!(b.len() as f32 > 0.8 * a.len() as f32 && b.len() <= a.len());
    for (k, db) in b.keypoints.iter().zip(&b.descriptors) {
        let (i, d) = nearest(&a, k.x, k.y);
        assert!(d < 1e-3, "moved by {d}");
        // The same point may carry several orientations: compare like with like.
        let twin = a.keypoints.iter().position(|q| {
            q.x == a.keypoints[i].x && q.y == a.keypoints[i].y && angle_gap(q.angle, k.angle) < 0.01
        });
        let Some(twin) = twin else {
            panic!("no keypoint at ({}, {}) with angle {}", k.x, k.y, k.angle)
        };
        assert!(distance(&a.descriptors[twin], db) <= 3.0);
    }
}

#[test]
fn output_follows_opencv_conventions() {
    let image = texture(160, 140);
    let features = Sift::new(SiftOptions::default()).detect_and_compute(&image);
    assert_eq!(features.keypoints.len(), features.descriptors.len());
    let sorted = features
        .keypoints
        .windows(2)
        .all(|w| (w[0].x, w[0].y) <= (w[1].x, w[1].y));
    assert!(sorted, "sorted by x, then y");
    for k in &features.keypoints {
        assert!((0.0..360.0).contains(&k.angle));
        assert!(k.x >= 0.0 && k.y >= 0.0 && k.x < 160.0 && k.y < 140.0);
        // Octave byte: −1 (upsampled) … ; layer 1…3 in the second byte.
        let octave = (k.octave & 0xff) as i8;
        let layer = (k.octave >> 8) & 0xff;
        assert!(
            (-1..8).contains(&octave) && (1..=3).contains(&layer),
            "{k:?}"
        );
        let expected_size = 1.6 * 2f32.powf(layer as f32 / 3.0) * 2f32.powi(octave as i32) * 2.0;
        assert!(
            (k.size / expected_size).log2().abs() <= 0.5 / 3.0 + 1e-3,
            "{k:?}"
        );
    }
    let unsorted_limit = Sift::new(SiftOptions {
        max_keypoints: Some(10),
        ..SiftOptions::default()
    })
    .detect_and_compute(&image);
    assert_eq!(unsorted_limit.len(), 10);
    let weakest_kept = unsorted_limit
        .keypoints
        .iter()
        .map(|k| k.response)
        .fold(f32::INFINITY, f32::min);
    let stronger = features
        .keypoints
        .iter()
        .filter(|k: &&Keypoint| k.response > weakest_kept)
        .count();
    assert!(stronger < 10, "the kept ten are the strongest");
}

#[test]
fn empty_and_tiny_images_give_no_keypoints() {
    let mut sift = Sift::new(SiftOptions::default());
    assert!(sift.detect_and_compute(&GrayImage::new(0, 0)).is_empty());
    assert!(sift.detect_and_compute(&GrayImage::new(3, 2)).is_empty());
    assert!(sift
        .detect_and_compute(&GrayImage::from_vec(1, 1, vec![7.0]).unwrap())
        .is_empty());
}

#[test]
fn a_filter_keeps_exactly_the_accepted_keypoints_with_their_descriptors() {
    let image = texture(160, 140);
    let mut sift = Sift::new(SiftOptions::default());
    let all = sift.detect_and_compute(&image);
    let left = sift.detect_and_compute_where(&image, |k| k.x < 80.0);
    let expected: Vec<(Keypoint, Descriptor)> = all
        .keypoints
        .iter()
        .copied()
        .zip(all.descriptors.iter().copied())
        .filter(|(k, _)| k.x < 80.0)
        .collect();
    let got: Vec<(Keypoint, Descriptor)> =
        left.keypoints.into_iter().zip(left.descriptors).collect();
    assert!(!got.is_empty() && got.len() < all.len());
    assert_eq!(got, expected);
}
