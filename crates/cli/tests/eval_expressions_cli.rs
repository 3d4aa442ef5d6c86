//! `visage eval expressions` as a user runs it: a few frames of a real take, rigidly, with the
//! renders saved; and a bad identity refused as bad input.

mod common;

use common::{s, visage};

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn eval_expressions_writes_results_plots_and_frames() {
    let models = visage_testdata::models_dir();
    let data = visage_testdata::shared_dir().join("data");
    let take = visage_testdata::require(data.join("arkit-takes/jmtechart_MySlate_3.csv"));
    let ict = data.join("ict-facekit/FaceXModel");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let args = [
        "eval",
        "expressions",
        s(&take),
        "--model",
        s(&ict),
        "--models",
        s(&models),
        "--out",
        s(&out),
        "--max-frames",
        "12",
        "--stride",
        "4",
        "--rigid",
        "--yaw",
        "20",
        "--save-frames",
        "2",
    ];
    let o = visage(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        table.contains("jmtechart_MySlate_3") && table.contains("jawOpen"),
        "{table}"
    );
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    assert_eq!(results["summary"]["frames"], 12);
    assert_eq!(
        results["summary"]["rest_frames"], 12,
        "rigid: every frame rests"
    );
    assert!(out
        .join("plots/jmtechart_MySlate_3/eyeBlinkLeft.svg")
        .is_file());
    for i in [0, 6] {
        let frame = out.join(format!("frames/jmtechart_MySlate_3_{i:05}.png"));
        assert!(frame.is_file(), "{} missing", frame.display());
    }
}

#[test]
fn eval_expressions_refuses_an_identity_that_is_not_a_number() {
    let tmp = tempfile::tempdir().unwrap();
    let take = tmp.path().join("take.csv");
    std::fs::write(&take, "Timecode,BlendShapeCount\n").unwrap();
    let o = visage(&[
        "eval",
        "expressions",
        s(&take),
        "--model",
        s(tmp.path()),
        "--out",
        s(&tmp.path().join("out")),
        "--identity",
        "somebody",
    ]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("--identity somebody"));
}
