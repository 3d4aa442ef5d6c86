//! Raw parity with the reference TFLite interpreter (`shared/reference/facemesh`): the landmark
//! network on `crop192.png` within 1e-2 crop pixels of `landmarks_raw.json` (max over all cases).

mod common;

use visage_face::LandmarkNetwork;

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn landmark_network_matches_tflite_on_every_case() {
    let (reference, models) = (common::reference_dir(), common::models_dir());
    let mut net = LandmarkNetwork::load(&models).unwrap();
    let mut worst = 0.0f64;
    for case in common::cases(&reference) {
        let crop = common::read_rgb(reference.join(&case).join("crop192.png"));
        let out = net.run_rgb8(crop.as_raw()).unwrap();
        let expected = common::read_json(reference.join(&case).join("landmarks_raw.json"));
        let pts = expected["landmarks_crop_px"].as_array().unwrap();
        assert_eq!(pts.len(), out.points.len());
        let mut case_max = 0.0f64;
        for (p, e) in out.points.iter().zip(pts) {
            for k in 0..3 {
                case_max = case_max.max((p[k] as f64 - e[k].as_f64().unwrap()).abs());
            }
        }
        let logit = expected["presence_logit"].as_f64().unwrap();
        println!(
            "{case}: max |Δ| = {case_max:.2e} crop px, presence logit {} vs {logit}",
            out.presence_logit
        );
        assert!(
            case_max < 1e-2,
            "{case}: max landmark difference {case_max}"
        );
        assert!(
            (out.presence_logit as f64 - logit).abs() < 1e-2,
            "{case}: presence logit"
        );
        worst = worst.max(case_max);
    }
    println!("worst case: {worst:.2e} crop px");
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn detector_best_anchor_matches_tflite_on_every_case() {
    let (reference, models) = (common::reference_dir(), common::models_dir());
    let mut det = visage_face::FaceDetector::load(&models).unwrap();
    for case in common::cases(&reference) {
        let input = common::read_rgb(reference.join(&case).join("det128.png"));
        let all = det.run_rgb8(input.as_raw()).unwrap();
        let (best, d) = all
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.score.total_cmp(&b.1.score))
            .unwrap();
        let e = common::read_json(reference.join(&case).join("detector_raw.json"));
        assert_eq!(
            best as u64,
            e["anchor_index"].as_u64().unwrap(),
            "{case}: best anchor"
        );
        let mut worst = (d.score as f64 - e["score"].as_f64().unwrap()).abs();
        for k in 0..2 {
            worst =
                worst.max((d.center[k] as f64 - e["box_center_norm"][k].as_f64().unwrap()).abs());
            worst = worst.max((d.size[k] as f64 - e["box_size_norm"][k].as_f64().unwrap()).abs());
        }
        for (p, q) in d
            .keypoints
            .iter()
            .zip(e["keypoints_norm"].as_array().unwrap())
        {
            for k in 0..2 {
                worst = worst.max((p[k] as f64 - q[k].as_f64().unwrap()).abs());
            }
        }
        println!("{case}: anchor {best}, max |Δ| = {worst:.2e} (normalised)");
        assert!(worst < 1e-3, "{case}: detector differs by {worst}");
    }
}
