//! Whole frames against MediaPipe's own solutions: FaceMesh's plain network against
//! `solution.json`, the attention face mesh with its irises against `solution_refined.json`
//! (`refine_landmarks=True`); mean landmark distance ≤ 1.5 px on every case. And the crop
//! geometry against the reference `crop192.png`.

mod common;

use visage_face::{FaceMesh, Roi};

/// Mean and largest distance (frame px) of `mesh`'s first face from `solution` on each case,
/// over the first `count` points; asserts both bounds of the module's docs.
fn compare_with_solution(mesh: &mut FaceMesh, solution: &str, count: usize) {
    let reference = common::reference_dir();
    for case in common::cases(&reference) {
        let frame = common::read_rgb(reference.join(&case).join("frame.png"));
        let faces = mesh.process(&frame).unwrap();
        assert!(!faces.is_empty(), "{case}: no face");
        let mut ours = faces[0].landmarks.mediapipe_points();
        if let Some(eyes) = &faces[0].eyes {
            // MediaPipe's refined irises follow the mesh: 468–472 the subject's right eye,
            // then the left, rim points image right, up, image left, down.
            for (eye, nose_first) in [(&eyes.right, true), (&eyes.left, false)] {
                let mut iris = eye.iris;
                if !nose_first {
                    iris.swap(1, 3);
                }
                ours.extend(iris.iter().map(|p| [p[0] + 0.5, p[1] + 0.5, p[2]]));
            }
        }
        let sol = common::read_json(reference.join(&case).join(solution));
        let pts = sol["landmarks_frame_px"].as_array().unwrap();
        assert!(
            ours.len() >= count && pts.len() >= count,
            "{case}: too few points"
        );
        let mut sum = 0.0;
        let mut worst = 0.0f64;
        for (p, q) in ours.iter().zip(pts).take(count) {
            let dx = p[0] as f64 - q[0].as_f64().unwrap();
            let dy = p[1] as f64 - q[1].as_f64().unwrap();
            let d = (dx * dx + dy * dy).sqrt();
            sum += d;
            worst = worst.max(d);
        }
        let mean = sum / count as f64;
        println!(
            "{case} against {solution}: {} face(s), mean {mean:.3} px, max {worst:.3} px",
            faces.len()
        );
        assert!(
            mean <= 1.5,
            "{case}: mean distance {mean} px (acceptance bound)"
        );
        // Regression pin: with MediaPipe's exact crop sampling the port agrees to ~0.05 px.
        assert!(
            mean <= 0.25,
            "{case}: mean distance {mean} px, was ≤ 0.05 when the crop convention matched"
        );
    }
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn landmarks_match_mediapipe_solution_on_every_frame() {
    let mut mesh = FaceMesh::load(&common::models_dir()).unwrap();
    compare_with_solution(&mut mesh, "solution.json", 468);
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn refined_landmarks_and_irises_match_mediapipes_refined_solution_on_every_frame() {
    let mut mesh = FaceMesh::load_attention(&common::models_dir()).unwrap();
    compare_with_solution(&mut mesh, "solution_refined.json", 478);
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared beside the checkout")]
fn crop_geometry_matches_reference_crop() {
    let reference = common::reference_dir();
    for case in common::cases(&reference) {
        let dir = reference.join(&case);
        let frame = common::read_rgb(dir.join("frame.png"));
        let crop = common::read_rgb(dir.join("crop192.png"));
        let t = common::read_json(dir.join("landmarks_raw.json"))["crop_to_frame"].clone();
        let (x0, y0, s) = (
            t["x0"].as_f64().unwrap() as f32,
            t["y0"].as_f64().unwrap() as f32,
            t["scale"].as_f64().unwrap() as f32,
        );
        let roi = Roi {
            center: [x0 + 96.0 * s, y0 + 96.0 * s],
            size: 192.0 * s,
            rotation: 0.0,
        };
        let mut out = vec![0.0; 192 * 192 * 3];
        visage_face::crop::crop_roi(&frame, &roi, 192, &mut out);
        let mad: f32 = out
            .iter()
            .zip(crop.as_raw())
            .map(|(a, &b)| (a * 255.0 - b as f32).abs())
            .sum::<f32>()
            / out.len() as f32;
        println!("{case}: mean |Δ| = {mad:.3} grey levels");
        assert!(
            mad < 1.0,
            "{case}: crop differs by {mad} grey levels on average"
        );
    }
}
