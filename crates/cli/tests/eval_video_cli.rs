//! `visage eval video` as a user runs it on a real clip: the table, results.json with every
//! baseline family and the pipeline's outputs per region, and the chart.

mod common;

use common::{s, visage};

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn eval_video_compares_the_temporal_model_with_the_baselines() {
    let models = visage_testdata::models_dir();
    let clip =
        visage_testdata::require(visage_testdata::shared_dir().join("data/video/lp_d18.mp4"));
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let args = [
        "eval",
        "video",
        s(&clip),
        "--out",
        s(&out),
        "--max-frames",
        "40",
        "--models",
        s(&models),
    ];
    let o = visage(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        table.contains("streaming") && table.contains("inner_lips"),
        "{table}"
    );
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let report = &results[0];
    assert_eq!(report["frames"], 40);
    let families: Vec<&str> = report["methods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["family"].as_str().unwrap())
        .collect();
    for f in ["ema", "one_euro", "kalman", "gaussian", "streaming", "clip"] {
        assert!(families.contains(&f), "{f} missing");
    }
    let streaming = report["comparisons"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["output"] == "streaming")
        .unwrap();
    // The smoother steadies the landmarks, within half a pixel of the tracked ones.
    assert!(
        streaming["reduction"].as_f64().unwrap() > 1.5,
        "{streaming}"
    );
    assert!(
        streaming["deviation_px"].as_f64().unwrap() < 0.5,
        "{streaming}"
    );
    let svg = std::fs::read_to_string(out.join("lp_d18_stability.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("one euro"));
}
