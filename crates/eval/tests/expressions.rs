//! The expression benchmark from pixels end to end on a short piece of a real ARKit take: the
//! rendered head is found on every frame, the head's rotation is read to within a few degrees
//! under the default ±40° / ±25° / ±15° motion, and the results file has every field the
//! benchmark promises.

use std::path::PathBuf;
use std::sync::Arc;

use visage_eval::{
    evaluate_expressions, face_texture, write_expression_results, ExpressionOptions, HeadRender,
    ReplayOptions,
};
use visage_morphable::{IctModel, ImportOptions};

/// Frames rendered and run (every second row of the take: 3.2 s at 15 fps).
const FRAMES: usize = 48;

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn a_take_replayed_on_a_rendered_head_is_read_frame_by_frame() {
    let shared = visage_testdata::shared_dir().join("data");
    let ict = shared.join("ict-facekit/FaceXModel");
    visage_testdata::require(ict.join("generic_neutral_mesh.obj"));
    let take = visage_testdata::require(shared.join("arkit-takes/alex_rom_3.csv"));
    let models = visage_testdata::models_dir();
    visage_testdata::require(models.join("face_landmark.tflite"));
    // One identity mode keeps the import short; the 53 expressions are all needed.
    let model = IctModel::load_with(
        &ict,
        &ImportOptions {
            max_identities: Some(1),
            expressions: Some(
                visage_rig::ICT_EXPRESSIONS
                    .iter()
                    .map(|s| s.to_string())
                    .collect(),
            ),
        },
    )
    .unwrap();
    let f = 0.5 * 640.0 / 27.5f64.to_radians().tan();
    let k = visage::Intrinsics::new(640, 480, f, f, 319.5, 239.5).unwrap();
    let render = Arc::new(HeadRender::new(model, &face_texture().unwrap(), k, 0.5).unwrap());
    let options = ExpressionOptions {
        replay: ReplayOptions {
            stride: 2,
            max_frames: Some(FRAMES),
            ..ReplayOptions::default()
        },
        models: Some(models),
        ..ExpressionOptions::default()
    };
    let takes = [take];
    let results = evaluate_expressions(&takes, &render, &options).unwrap();
    let s = &results.summary;
    assert_eq!(s.frames, FRAMES);
    assert_eq!(s.frames_with_face, FRAMES, "a face on every frame");
    let rotation = s.head_rotation_rmse_deg.unwrap();
    assert!(rotation < 10.0, "head rotation error {rotation}°");
    let identity = s.identity_error_mm.unwrap();
    assert!(identity < 10.0, "identity error {identity} mm");
    let mae = s.mae.unwrap();
    assert!(mae < 0.3, "mean absolute error {mae}");

    let out = tempfile::tempdir().unwrap();
    write_expression_results(out.path(), &results).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("results.json")).unwrap())
            .unwrap();
    for field in [
        "mae",
        "blink_hit_rate",
        "false_closure_rate",
        "rigid_leak_p99",
        "head_rotation_rmse_deg",
        "identity_error_mm",
    ] {
        assert!(
            json["summary"].get(field).is_some(),
            "summary.{field} missing"
        );
    }
    let jaw = &json["takes"][0]["shapes"]["jawOpen"];
    assert!(jaw["mae"].is_number() && jaw.get("r").is_some(), "{jaw}");
    let plot: PathBuf = out.path().join("plots/alex_rom_3/jawOpen.svg");
    assert!(std::fs::read_to_string(plot).unwrap().starts_with("<svg"));
}
