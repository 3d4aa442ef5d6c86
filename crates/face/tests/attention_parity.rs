//! The attention face mesh against MediaPipe (`tests/data/attention_reference.json`, written by
//! `scripts/dev/attention_reference.py`: MediaPipe 0.10.21's `FaceLandmarkCpu` with attention
//! on each `shared/reference/facemesh/CASE/crop192.png`): the 478 refined landmarks within
//! 1e-2 crop px (x, y, z) on every case; and a truncated or altered model file is an error.

mod common;

use visage_face::attention_network::{
    LEFT_EYE_MESH_INDICES, LIPS_MESH_INDICES, RIGHT_EYE_MESH_INDICES,
};
use visage_face::{AttentionNetwork, ModelFile, NUM_LANDMARKS, NUM_REFINED_LANDMARKS};

/// Bound on every coordinate's difference, crop pixels.
const TOLERANCE: f64 = 1e-2;

/// The groups the differences are reported by: the mesh points no head refines, the lips, the
/// eyes, the irises.
fn group(i: usize) -> usize {
    if i >= NUM_LANDMARKS {
        3
    } else if LIPS_MESH_INDICES.contains(&i) {
        1
    } else if RIGHT_EYE_MESH_INDICES.contains(&i) || LEFT_EYE_MESH_INDICES.contains(&i) {
        2
    } else {
        0
    }
}

const GROUPS: [&str; 4] = ["mesh", "lips", "eyes", "irises"];

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn refined_landmarks_match_mediapipe_on_every_case() {
    let (reference, models) = (common::reference_dir(), common::models_dir());
    let expected = common::read_json(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/attention_reference.json"),
    );
    let mut net = AttentionNetwork::load(&models).unwrap();
    let mut worst = [0.0f64; 4];
    let cases = common::cases(&reference);
    assert!(!cases.is_empty());
    for case in cases {
        let crop = common::read_rgb(reference.join(&case).join("crop192.png"));
        let out = net.run_rgb8(crop.as_raw()).unwrap();
        let refined = out.refined();
        let points = expected["cases"][&case]
            .as_array()
            .unwrap_or_else(|| panic!("{case}: no reference"));
        assert_eq!(points.len(), NUM_REFINED_LANDMARKS, "{case}");
        assert_eq!(refined.len(), NUM_REFINED_LANDMARKS, "{case}");
        let mut max = [0.0f64; 4];
        for (i, (p, e)) in refined.iter().zip(points).enumerate() {
            for k in 0..3 {
                let d = (p[k] as f64 - e[k].as_f64().unwrap()).abs();
                max[group(i)] = max[group(i)].max(d);
            }
        }
        println!(
            "{case}: max |Δ| mesh {:.1e}, lips {:.1e}, eyes {:.1e}, irises {:.1e} crop px; \
             presence logit {:.2}",
            max[0], max[1], max[2], max[3], out.presence_logit
        );
        for (g, m) in max.iter().enumerate() {
            assert!(
                *m < TOLERANCE,
                "{case}: {} differ by {m} crop px",
                GROUPS[g]
            );
            worst[g] = worst[g].max(*m);
        }
        // Every reference crop holds a face.
        assert!(
            out.presence_logit.is_finite() && out.presence() > 0.99,
            "{case}: presence logit {}",
            out.presence_logit
        );
    }
    println!(
        "worst: mesh {:.1e}, lips {:.1e}, eyes {:.1e}, irises {:.1e} crop px",
        worst[0], worst[1], worst[2], worst[3]
    );
}

#[test]
#[cfg_attr(not(model_files), ignore = "needs the model files (scripts/setup.sh)")]
fn a_truncated_or_altered_model_is_an_error() {
    let bytes = ModelFile::FaceLandmarkWithAttention
        .read(&common::models_dir())
        .unwrap();
    // Cut short: an error, never a panic (the flatbuffer's root table is near its start and
    // the weights fill the rest, so a cut leaves references past the end; the last bytes
    // are padding, whose loss is harmless).
    let n = bytes.len();
    for cut in [0, 7, 8, 100, 4096, n / 3, n / 2, n - 4096] {
        assert!(
            AttentionNetwork::from_bytes(&bytes[..cut]).is_err(),
            "{cut} bytes"
        );
    }
    // An option name changed in Landmarks2TransformMatrix's FlexBuffer: named in the error.
    let key = b"left_rotation_idx";
    let at = bytes
        .windows(key.len())
        .position(|w| w == key)
        .expect("the options are in the file");
    let mut altered = bytes.clone();
    altered[at + key.len() - 1] = b'y';
    let e = AttentionNetwork::from_bytes(&altered)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("face_landmark_with_attention.tflite")
            && e.contains("Landmarks2TransformMatrix")
            && e.contains("unknown option left_rotation_idy"),
        "{e}"
    );
    // The plain mesh network is not the attention one.
    let plain = ModelFile::FaceLandmark.read(&common::models_dir()).unwrap();
    let e = AttentionNetwork::from_bytes(&plain)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no output named output_mesh_identity"), "{e}");
}
