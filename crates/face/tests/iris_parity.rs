//! The iris network against the reference TFLite interpreter and MediaPipe
//! (`shared/reference/facemesh`, section "Eyes" of its README), every case, both eyes:
//! - raw: the network on `eye64_*.png` within 1e-2 crop px of `iris_raw_*.json`;
//! - crop: our eye crop of `frame.png` from the landmarks of `solution_refined.json` has the
//!   reference's crop-to-frame map, reproduces `eye64_*.png` to OpenCV's rounding, and gives the
//!   reference's iris centre in the frame;
//! - end to end: from our own tracked landmarks on `frame.png`, the iris centres lie within a few
//!   pixels of MediaPipe's refined solution (a different network, the attention model) and
//!   close to the iris network's own reference output.

mod common;

use std::path::Path;

use serde_json::Value;
use visage_face::{Eye, EyeCrop, FaceMesh, FaceTracker, IrisLandmarker, IrisNetwork, IRIS_INPUT};

fn side(eye: Eye) -> &'static str {
    match eye {
        Eye::Right => "right",
        Eye::Left => "left",
    }
}

fn points(v: &Value) -> Vec<[f64; 3]> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|p| [0, 1, 2].map(|k| p[k].as_f64().unwrap()))
        .collect()
}

/// The refined solution's 478 points in visage's pixel convention (MediaPipe's − ½).
fn refined_points(case_dir: &Path) -> Vec<[f32; 3]> {
    let sol = common::read_json(case_dir.join("solution_refined.json"));
    points(&sol["landmarks_frame_px"])
        .into_iter()
        .map(|p| [p[0] as f32 - 0.5, p[1] as f32 - 0.5, p[2] as f32])
        .collect()
}

/// The reference crop-to-frame map of `iris_raw_*.json`.
fn reference_crop(raw: &Value) -> EyeCrop {
    let t = &raw["crop_to_frame"];
    EyeCrop {
        x0: t["x0"].as_f64().unwrap() as f32,
        y0: t["y0"].as_f64().unwrap() as f32,
        scale: t["scale"].as_f64().unwrap() as f32,
        mirrored: t["mirrored"].as_bool().unwrap(),
    }
}

/// The reference iris centre (the iris network on `eye64_*.png`) in frame px, visage convention.
fn reference_center(raw: &Value) -> [f32; 3] {
    let c = points(&raw["iris_crop_px"])[0];
    reference_crop(raw).to_frame([c[0] as f32, c[1] as f32, c[2] as f32])
}

fn distance(a: [f32; 3], b: [f32; 3]) -> f32 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn iris_network_matches_tflite_on_every_case() {
    let (reference, models) = (common::reference_dir(), common::models_dir());
    let mut net = IrisNetwork::load(&models).unwrap();
    let mut worst = 0.0f64;
    for case in common::cases(&reference) {
        for eye in Eye::BOTH {
            let dir = reference.join(&case);
            let input = common::read_rgb(dir.join(format!("eye64_{}.png", side(eye))));
            let out = net.run_rgb8(input.as_raw()).unwrap();
            let raw = common::read_json(dir.join(format!("iris_raw_{}.json", side(eye))));
            let contour = points(&raw["eye_contour_crop_px"]);
            let iris = points(&raw["iris_crop_px"]);
            assert_eq!(contour.len(), out.contour.len(), "{case}: contour points");
            assert_eq!(iris.len(), out.iris.len(), "{case}: iris points");
            let mut max = 0.0f64;
            for (p, e) in out
                .contour
                .iter()
                .chain(&out.iris)
                .zip(contour.iter().chain(&iris))
            {
                for k in 0..3 {
                    max = max.max((p[k] as f64 - e[k]).abs());
                }
            }
            println!("{case} {}: max |Δ| = {max:.2e} crop px", side(eye));
            assert!(
                max < 1e-2,
                "{case} {}: max difference {max} crop px",
                side(eye)
            );
            worst = worst.max(max);
        }
    }
    println!("worst case: {worst:.2e} crop px");
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn eye_crop_matches_reference_crop_and_mapping() {
    let (reference, models) = (common::reference_dir(), common::models_dir());
    let mut iris = IrisLandmarker::load(&models).unwrap();
    let mut buf = vec![0.0; IRIS_INPUT * IRIS_INPUT * 3];
    for case in common::cases(&reference) {
        let dir = reference.join(&case);
        let frame = common::read_rgb(dir.join("frame.png"));
        let landmarks = refined_points(&dir);
        for eye in Eye::BOTH {
            let raw = common::read_json(dir.join(format!("iris_raw_{}.json", side(eye))));
            let expected = reference_crop(&raw);
            let crop = EyeCrop::from_landmarks(&landmarks, eye).unwrap();
            assert_eq!(crop.mirrored, expected.mirrored);
            let map = (crop.x0 - expected.x0)
                .abs()
                .max((crop.y0 - expected.y0).abs())
                .max(64.0 * (crop.scale - expected.scale).abs());
            assert!(map < 1e-3, "{case} {}: crop map off by {map} px", side(eye));

            let png = common::read_rgb(dir.join(format!("eye64_{}.png", side(eye))));
            crop.sample(&frame, &mut buf);
            let (mut sum, mut max) = (0.0f32, 0.0f32);
            for (a, &b) in buf.iter().zip(png.as_raw()) {
                let d = (a * 255.0 - b as f32).abs();
                sum += d;
                max = max.max(d);
            }
            let mean = sum / buf.len() as f32;

            let ours = iris.eye(&frame, &landmarks, eye).unwrap();
            let centre = distance(ours.iris_center(), reference_center(&raw));
            println!(
                "{case} {}: crop mean |Δ| {mean:.3}, max {max:.2} grey levels; iris centre \
                 {centre:.4} px from the reference mapping; radius {:.2} px",
                side(eye),
                ours.iris_radius()
            );
            // Measured: mean 0.20–0.29, max ≤ 4.3 levels (OpenCV rounds positions to 1/32 px).
            assert!(mean < 0.5, "{case} {}: crop mean |Δ| {mean}", side(eye));
            assert!(max < 8.0, "{case} {}: crop max |Δ| {max}", side(eye));
            assert!(
                centre < 0.15,
                "{case} {}: iris centre {centre} px",
                side(eye)
            );
        }
    }
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn tracked_iris_centres_match_mediapipe() {
    let (reference, models) = (common::reference_dir(), common::models_dir());
    let mesh = FaceMesh::load(&models).unwrap();
    assert!(
        mesh.iris.is_some(),
        "the iris network is in the model folder"
    );
    let (mut worst_refined, mut worst_same) = (0.0f32, 0.0f32);
    for case in common::cases(&reference) {
        let dir = reference.join(&case);
        let frame = common::read_rgb(dir.join("frame.png"));
        let mut tracker = FaceTracker::new(mesh.clone());
        let face = tracker.track(&frame).unwrap().face.expect("a face");
        let eyes = face.eyes.expect("eyes with the iris network loaded");
        let refined = refined_points(&dir);
        for (eye, centre_index) in [(Eye::Right, 468), (Eye::Left, 473)] {
            let ours = eyes.get(eye).iris_center();
            let raw = common::read_json(dir.join(format!("iris_raw_{}.json", side(eye))));
            let to_refined = distance(ours, refined[centre_index]);
            let to_same = distance(ours, reference_center(&raw));
            let (crop, reference_crop) = (
                eyes.get(eye).crop.expect("the iris network's crop"),
                reference_crop(&raw),
            );
            let crop_shift = (crop.x0 - reference_crop.x0)
                .hypot(crop.y0 - reference_crop.y0)
                .max(64.0 * (crop.scale - reference_crop.scale).abs());
            println!(
                "{case} {}: iris centre ({:.1}, {:.1}): {to_refined:.2} px from the refined \
                 solution, {to_same:.3} px from the iris network's reference (crop {crop_shift:.2} px \
                 away: corners of the attention model)",
                side(eye),
                ours[0],
                ours[1]
            );
            worst_refined = worst_refined.max(to_refined);
            worst_same = worst_same.max(to_same);
        }
        // The subject's right eye is on the image's left.
        assert!(
            eyes.right.iris_center()[0] < eyes.left.iris_center()[0],
            "{case}"
        );
    }
    println!("worst: {worst_refined:.2} px (refined solution), {worst_same:.3} px (same network)");
    assert!(
        worst_refined < 4.0,
        "iris centre {worst_refined} px from MediaPipe's"
    );
    assert!(
        worst_same < 2.0,
        "iris centre {worst_same} px from the iris reference"
    );
}
