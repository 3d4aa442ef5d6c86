//! The full-range face detector against MediaPipe 0.10.21 (`tests/data/full_range_reference.json`,
//! written by `scripts/dev/full_range_reference.py`; the images are rebuilt here from `../shared`
//! exactly as the script builds them):
//! - raw: the network on one fixed 192×192 input (the portrait area-resized by 3/8) against the
//!   TFLite interpreter: the top anchors' logits and 16 regressors, every 32nd logit;
//! - detections: MediaPipe's `solutions.face_detection` (full range) on whole images: the same
//!   number of faces, box corners within 1 px, keypoints within 1.5 px, scores within 0.02;
//! - tiles: the same on each 640-px tile of a 1280×720 canvas with a 41-px face, which MediaPipe
//!   (and visage) miss on the whole frame; `detect_tiled` finds it.

mod common;

use image::{Rgb, RgbImage};
use serde_json::Value;
use visage_face::detector::tiles;
use visage_face::{Detection, FaceDetector};

const REFERENCE: &str = "tests/data/full_range_reference.json";

fn reference() -> Value {
    common::read_json(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(REFERENCE))
}

fn usizes(v: &Value) -> Vec<usize> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap() as usize)
        .collect()
}

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// For each output pixel along an axis of `n_in` input pixels resized by `num/den`: the input
/// pixels it overlaps (input `i` spans `[i·num, (i+1)·num)`, output `o` spans
/// `[o·den, (o+1)·den)`) and the integer overlaps, which sum to `den`.
fn area_weights(n_in: usize, num: usize, den: usize) -> Vec<Vec<(usize, u64)>> {
    (0..n_in * num / den)
        .map(|o| {
            let (a, b) = (o * den, (o + 1) * den);
            (a / num..(b.div_ceil(num)).min(n_in))
                .map(|i| (i, (b.min((i + 1) * num) - a.max(i * num)) as u64))
                .filter(|&(_, w)| w > 0)
                .collect()
        })
        .collect()
}

/// Exact area-average resize by `num/den` in integers, rounded half up (the script's
/// `area_resize`).
fn area_resize(img: &RgbImage, num: usize, den: usize) -> RgbImage {
    let wy = area_weights(img.height() as usize, num, den);
    let wx = area_weights(img.width() as usize, num, den);
    let d2 = (den * den) as u64;
    RgbImage::from_fn(wx.len() as u32, wy.len() as u32, |ox, oy| {
        let mut acc = [0u64; 3];
        for &(iy, a) in &wy[oy as usize] {
            for &(ix, b) in &wx[ox as usize] {
                let p = img.get_pixel(ix as u32, iy as u32);
                for c in 0..3 {
                    acc[c] += a * b * p[c] as u64;
                }
            }
        }
        Rgb(acc.map(|s| ((s + d2 / 2) / d2) as u8))
    })
}

/// The test image of a case, as the script builds it.
fn build(case: &Value, canvas: &Value) -> RgbImage {
    let shared = visage_testdata::shared_dir();
    if case["kind"] == "frame" {
        return common::read_rgb(shared.join(case["path"].as_str().unwrap()));
    }
    let size = usizes(&canvas["size"]);
    let grey = canvas["grey"].as_u64().unwrap() as u8;
    let mut img = RgbImage::from_pixel(size[0] as u32, size[1] as u32, Rgb([grey; 3]));
    let portrait = common::read_rgb(shared.join(canvas["portrait"].as_str().unwrap()));
    let scale = usizes(&case["scale"]);
    let small = area_resize(&portrait, scale[0], scale[1]);
    for at in case["paste"].as_array().unwrap() {
        let at = usizes(at);
        image::imageops::replace(&mut img, &small, at[0] as i64, at[1] as i64);
    }
    img
}

/// Largest differences between matched detections: (box corner px, keypoint px, score).
fn compare(ours: &[Detection], theirs: &Value, what: &str) -> [f64; 3] {
    let theirs = theirs.as_array().unwrap();
    assert_eq!(
        ours.len(),
        theirs.len(),
        "{what}: {} faces, MediaPipe {} ({ours:?})",
        ours.len(),
        theirs.len()
    );
    let mut worst = [0.0f64; 3];
    for t in theirs {
        let b = f64s(&t["box"]);
        let corners = [b[0], b[1], b[0] + b[2], b[1] + b[3]];
        let centre = [b[0] + b[2] / 2.0, b[1] + b[3] / 2.0];
        let d = ours
            .iter()
            .min_by(|p, q| {
                let dist = |d: &Detection| {
                    (d.center[0] as f64 - centre[0]).hypot(d.center[1] as f64 - centre[1])
                };
                dist(p).total_cmp(&dist(q))
            })
            .unwrap();
        let [x, y, w, h] = d.bbox().map(|v| v as f64);
        for (a, e) in [x, y, x + w, y + h].iter().zip(corners) {
            worst[0] = worst[0].max((a - e).abs());
        }
        for (p, q) in d.keypoints.iter().zip(t["keypoints"].as_array().unwrap()) {
            let q = f64s(q);
            worst[1] = worst[1].max((p[0] as f64 - q[0]).hypot(p[1] as f64 - q[1]));
        }
        worst[2] = worst[2].max((d.score as f64 - t["score"].as_f64().unwrap()).abs());
    }
    println!(
        "{what}: {} face(s); max |Δ| box corner {:.3} px, keypoint {:.3} px, score {:.4}",
        ours.len(),
        worst[0],
        worst[1],
        worst[2]
    );
    assert!(
        worst[0] <= 1.0 && worst[1] <= 1.5 && worst[2] <= 0.02,
        "{what}: differs from MediaPipe by {worst:?}"
    );
    worst
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn raw_outputs_match_tflite() {
    let models = common::models_dir();
    let reference = reference();
    let raw = &reference["raw"];
    let portrait = common::read_rgb(
        visage_testdata::shared_dir().join(reference["canvas"]["portrait"].as_str().unwrap()),
    );
    let input = area_resize(&portrait, 3, 8);
    assert_eq!(input.dimensions(), (192, 192));
    let mut det = FaceDetector::load_full_range(&models).unwrap();
    det.run_rgb8(input.as_raw()).unwrap();
    let (reg, cls) = det.raw_outputs();
    assert_eq!((reg.len(), cls.len()), (2304 * 16, 2304));
    let (mut logit, mut regressor) = (0.0f64, 0.0f64);
    let top = raw["top_anchors"].as_array().unwrap();
    let best = (0..cls.len())
        .max_by(|&a, &b| cls[a].total_cmp(&cls[b]))
        .unwrap();
    assert_eq!(
        best as u64,
        top[0]["anchor"].as_u64().unwrap(),
        "best anchor"
    );
    for a in top {
        let i = a["anchor"].as_u64().unwrap() as usize;
        logit = logit.max((cls[i] as f64 - a["logit"].as_f64().unwrap()).abs());
        for (k, e) in f64s(&a["regressors"]).into_iter().enumerate() {
            regressor = regressor.max((reg[i * 16 + k] as f64 - e).abs());
        }
    }
    for (j, e) in f64s(&raw["logits_every_32nd"]).into_iter().enumerate() {
        logit = logit.max((cls[32 * j] as f64 - e).abs());
    }
    println!(
        "raw outputs vs {}: max |Δ| logit {logit:.2e}, regressor {regressor:.2e} input px",
        raw["runtime"]
    );
    assert!(logit < 1e-2 && regressor < 2e-2, "{logit} {regressor}");
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn detections_match_mediapipe_and_tiles_find_small_faces() {
    let models = common::models_dir();
    let reference = reference();
    let mut full = FaceDetector::load_full_range(&models).unwrap();
    let mut short = FaceDetector::load(&models).unwrap();
    let mut worst = [0.0f64; 3];
    let mut track = |w: [f64; 3]| {
        for k in 0..3 {
            worst[k] = worst[k].max(w[k]);
        }
    };
    for case in reference["cases"].as_array().unwrap() {
        let name = case["name"].as_str().unwrap();
        let img = build(case, &reference["canvas"]);
        assert_eq!(
            [img.width() as usize, img.height() as usize],
            usizes(&case["size"])[..]
        );
        track(compare(
            &full.detect(&img).unwrap(),
            &case["detections"],
            name,
        ));
        println!(
            "{name}: the short-range detector finds {} face(s)",
            short.detect(&img).unwrap().len()
        );
        let Some(tile) = case["tile"].as_u64() else {
            continue;
        };
        let tile = tile as u32;
        let rects = tiles(img.width(), img.height(), tile);
        let expected = case["tiles"].as_array().unwrap();
        assert_eq!(rects.len(), expected.len(), "{name}: tiles");
        let mut in_tiles = Vec::new();
        for (r, e) in rects.iter().zip(expected) {
            assert_eq!(r.map(|v| v as usize)[..], usizes(&e["rect"])[..], "{name}");
            let crop = image::imageops::crop_imm(&img, r[0], r[1], r[2], r[3]).to_image();
            let what = format!("{name} tile {},{}", r[0], r[1]);
            track(compare(
                &full.detect(&crop).unwrap(),
                &e["detections"],
                &what,
            ));
            for d in e["detections"].as_array().unwrap() {
                let b = f64s(&d["box"]);
                in_tiles.push([b[0] + r[0] as f64, b[1] + r[1] as f64, b[2]]);
            }
        }
        // The small face MediaPipe finds in the tiles is among what detect_tiled returns.
        let tiled = full.detect_tiled(&img, tile).unwrap();
        assert!(
            !in_tiles.is_empty(),
            "{name}: MediaPipe found no face in the tiles"
        );
        for [x, y, w] in in_tiles {
            let hit = tiled.iter().find(|d| {
                let b = d.bbox();
                (b[0] as f64 - x).abs() < 2.0 && (b[1] as f64 - y).abs() < 2.0
            });
            let hit = hit.unwrap_or_else(|| panic!("{name}: no tiled detection at {x}, {y}"));
            println!(
                "{name}: detect_tiled finds the {:.1}-px face (MediaPipe in the tiles: {w:.1} px), \
                 score {:.3}",
                hit.size[0], hit.score
            );
            assert!((hit.size[0] as f64 - w).abs() < 2.0 && hit.size[0] < 50.0);
        }
    }
    println!(
        "all cases: max |Δ| box corner {:.3} px, keypoint {:.3} px, score {:.4}",
        worst[0], worst[1], worst[2]
    );
}

#[test]
fn area_resize_is_an_exact_average() {
    // 4 → 2 (1/2): pairs averaged, halves rounded up; 3 → 2 (2/3): overlaps 2+1 and 1+2.
    let img = RgbImage::from_fn(4, 1, |x, _| Rgb([[0, 1, 10, 20][x as usize]; 3]));
    let half = area_resize(&img, 1, 2);
    assert_eq!(half.dimensions(), (2, 0)); // one row → zero rows at 1/2
    let img = RgbImage::from_fn(4, 2, |x, _| Rgb([[0, 1, 10, 20][x as usize]; 3]));
    let half = area_resize(&img, 1, 2);
    assert_eq!((half.get_pixel(0, 0)[0], half.get_pixel(1, 0)[0]), (1, 15));
    let img = RgbImage::from_fn(3, 3, |x, _| Rgb([[0, 30, 90][x as usize]; 3]));
    let two = area_resize(&img, 2, 3);
    // Output 0 covers input 0 (weight 2) and 1 (weight 1): (0·2 + 30) / 3 = 10; output 1: 70.
    assert_eq!((two.get_pixel(0, 0)[0], two.get_pixel(1, 1)[0]), (10, 70));
}
