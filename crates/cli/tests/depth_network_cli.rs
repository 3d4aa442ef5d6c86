//! `visage run --depth MODEL.onnx` as a user runs it: the test network of visage-depth
//! (`crates/depth/tests/data/make_networks.py`) on both shared clips, its per-frame alignment
//! reported and the meshes metric; networks that cannot be used refused with their file named.

mod common;

use common::{s, visage};

use std::path::{Path, PathBuf};

use serde_json::Value;

fn network(name: &str) -> PathBuf {
    visage_testdata::workspace_root()
        .join("crates/depth/tests/data")
        .join(name)
}

/// MediaPipe's landmarks at the face's widest, the cheeks' contour beside the ears.
const CHEEK_LANDMARKS: [usize; 2] = [234, 454];

/// `visage run` with the test network on the first `frames` frames of `clip`: the per-frame
/// face widths (metres, from the point cache) and metrics.json.
fn run_with_network(clip: &str, frames: usize) -> (Vec<f64>, Value) {
    let models = visage_testdata::models_dir();
    for file in visage_testdata::MODEL_FILES {
        visage_testdata::require(models.join(file));
    }
    let clip =
        visage_testdata::require(visage_testdata::shared_dir().join("data/video").join(clip));
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let frames = frames.to_string();
    let o = visage(&[
        "run",
        s(&clip),
        "--depth",
        s(&network("inverse_depth.onnx")),
        "--out",
        s(&out),
        "--max-frames",
        &frames,
        "--quiet",
        "--models",
        s(&models),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cache = visage_mesh::io::read_pc2(&out.join("sequence.pc2")).unwrap();
    let widths = (0..cache.samples())
        .map(|k| {
            let p = cache.sample(k);
            let [a, b] = CHEEK_LANDMARKS.map(|i| [p[3 * i], p[3 * i + 1], p[3 * i + 2]]);
            (0..3)
                .map(|c| (a[c] as f64 - b[c] as f64).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    let metrics: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    (widths, metrics)
}

#[track_caller]
fn check_metric_and_aligned(widths: &[f64], metrics: &Value, frames: usize) {
    assert_eq!(widths.len(), frames);
    for (k, w) in widths.iter().enumerate() {
        assert!((0.12..=0.18).contains(w), "frame {k}: face width {w} m");
    }
    let summary = &metrics["summary"]["depth_alignment"];
    assert_eq!(summary["frames"].as_u64(), Some(frames as u64), "{summary}");
    assert_eq!(summary["failed"].as_u64(), Some(0), "{summary}");
    for f in metrics["frames"].as_array().unwrap() {
        let a = &f["depth_alignment"];
        let residual = a["residual_mm"].as_f64().unwrap();
        assert!(residual.is_finite() && residual > 0.0, "{a}");
        assert!(a["inliers"].as_u64().unwrap() > 50, "{a}");
        assert_eq!(f["status"], "solved");
    }
    assert!(metrics["parameters"]["depth"]
        .as_str()
        .unwrap()
        .ends_with("inverse_depth.onnx"));
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn the_test_network_runs_end_to_end_on_both_clips_and_the_meshes_are_metric() {
    for clip in ["lp_d18.mp4", "lp_d13.mp4"] {
        let (widths, metrics) = run_with_network(clip, 20);
        check_metric_and_aligned(&widths, &metrics, 20);
    }
}

/// The error `visage run --depth NET` gives (and its exit code), with `extra` files beside.
fn refused(net: &Path) -> (i32, String) {
    let tmp = tempfile::tempdir().unwrap();
    let image = tmp.path().join("face.png");
    image::RgbImage::new(64, 64).save(&image).unwrap();
    let o = visage(&[
        "run",
        s(&image),
        "--depth",
        s(net),
        "--out",
        s(&tmp.path().join("out")),
        "--quiet",
    ]);
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn networks_that_cannot_be_used_are_refused_before_any_work_naming_the_file() {
    for (name, says) in [
        ("missing.onnx", "No such file"),
        ("rank3_input.onnx", "rank 3"),
        ("unsupported_op.onnx", "MaxUnpool"),
        ("wrong_output.onnx", "aspect ratio"),
    ] {
        let (code, stderr) = refused(&network(name));
        assert_eq!(code, 2, "{name}: {stderr}");
        assert!(
            stderr.contains(name) && stderr.contains(says) && stderr.contains("--depth"),
            "{name}: {stderr}"
        );
    }
}
