//! The expression benchmark from pixels end to end on a short piece of a real ARKit take: the
//! rendered head is found on every frame, the head's rotation is read to within a few degrees
//! under the default ±40° / ±25° / ±15° motion, and the results file has every field the
//! benchmark promises; a neutral head turned rigidly reads less expression with the rig's
//! pose-leak table than without it, and a head that only talks reads less of the upper face
//! with the mouth-leak table.

use std::path::PathBuf;
use std::sync::Arc;

use visage_eval::{
    evaluate_expressions, face_texture, write_expression_results, ExpressionOptions, HeadMotion,
    HeadRender, ReplayOptions,
};
use visage_morphable::{IctModel, ImportOptions};

/// Frames rendered and run (every second row of the take: 3.2 s at 15 fps).
const FRAMES: usize = 48;
/// Frames of the rigid turn.
const RIGID_FRAMES: usize = 120;
/// What the rigid turn's leak (99th percentile) must stay under with the table.
const LEAK_BOUND: f64 = 0.2;
/// The talking head's first row: where the take's range of motion works the jaw and lips.
const TALKING_START: usize = 1600;

/// The head renderer of ICT-FaceKit's identity 0 and the paths of the take and the model
/// files.
fn setup() -> (Arc<HeadRender>, PathBuf, PathBuf) {
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
    (render, take, models)
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn a_take_replayed_on_a_rendered_head_is_read_frame_by_frame() {
    let (render, take, models) = setup();
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
    let from_rest = s.mae_from_rest.unwrap();
    assert!(from_rest < 0.3, "mean absolute error from rest {from_rest}");

    let out = tempfile::tempdir().unwrap();
    write_expression_results(out.path(), &results).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("results.json")).unwrap())
            .unwrap();
    for field in [
        "mae",
        "mae_from_rest",
        "mae_floor",
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
    assert!(jaw["mae_from_rest"].is_number(), "{jaw}");
    assert!(jaw["mae_floor"].is_number(), "{jaw}");
    let plot: PathBuf = out.path().join("plots/alex_rom_3/jawOpen.svg");
    assert!(std::fs::read_to_string(plot).unwrap().starts_with("<svg"));
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn a_rigid_turn_leaks_less_with_the_pose_leak_taken_off() {
    let (render, take, models) = setup();
    // A neutral head (identity 0, not among the table's training heads) turned by ±38° yaw,
    // ±20° pitch and ±10° roll: every eighth row of 32 s of the take's clock.
    let leak = |keep_pose_leak| {
        let options = ExpressionOptions {
            replay: ReplayOptions {
                motion: HeadMotion {
                    yaw_deg: 38.0,
                    pitch_deg: 20.0,
                    roll_deg: 10.0,
                    ..HeadMotion::default()
                },
                rigid: Some(None),
                stride: 8,
                max_frames: Some(RIGID_FRAMES),
                ..ReplayOptions::default()
            },
            models: Some(models.clone()),
            keep_pose_leak,
            ..ExpressionOptions::default()
        };
        let results = evaluate_expressions(std::slice::from_ref(&take), &render, &options).unwrap();
        assert_eq!(results.summary.frames_with_face, RIGID_FRAMES);
        results.summary.rigid_leak_p99.unwrap()
    };
    let (without, with) = (leak(true), leak(false));
    eprintln!("rigid leak p99: {without:.3} without the table, {with:.3} with it");
    assert!(
        with < 0.9 * without && with < LEAK_BOUND,
        "rigid leak p99 {with} with the table, {without} without"
    );
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn a_talking_head_reads_less_upper_face_with_the_mouth_leak_taken_off() {
    let (render, take, models) = setup();
    // Identity 0 (not among the table's training heads) plays the take's mouth alone, from
    // its jaw and lip range of motion, under the default head motion: every fourth row.
    let read = |keep_mouth_leak| {
        let options = ExpressionOptions {
            replay: ReplayOptions {
                only: Some(
                    (0..visage_rig::ARKIT_BLENDSHAPE_COUNT)
                        .filter(|&i| visage_rig::is_mouth(i))
                        .collect(),
                ),
                start: TALKING_START,
                stride: 4,
                max_frames: Some(RIGID_FRAMES),
                ..ReplayOptions::default()
            },
            models: Some(models.clone()),
            keep_mouth_leak,
            ..ExpressionOptions::default()
        };
        let results = evaluate_expressions(std::slice::from_ref(&take), &render, &options).unwrap();
        let curves = results.takes.into_iter().next().unwrap().curves;
        assert!(curves
            .played
            .iter()
            .all(|p| (0..p.len()).all(|i| visage_rig::is_mouth(i) || p[i] == 0.0)));
        curves.read
    };
    let (without, with) = (read(true), read(false));
    let total = |read: &[[f32; visage_rig::ARKIT_BLENDSHAPE_COUNT]], pick: fn(usize) -> bool| {
        read.iter()
            .flat_map(|r| {
                r.iter()
                    .enumerate()
                    .filter(|(i, _)| pick(*i))
                    .map(|(_, w)| f64::from(*w))
            })
            .sum::<f64>()
    };
    let (upper_without, upper_with) = (
        total(&without, visage_rig::is_upper_face),
        total(&with, visage_rig::is_upper_face),
    );
    eprintln!("upper face's weights summed over the frames: {upper_without:.2} without the table, {upper_with:.2} with it");
    assert!(
        upper_with < 0.8 * upper_without,
        "{upper_with} against {upper_without}"
    );
    // The mouth's own weights are the same run for run.
    assert_eq!(
        total(&with, visage_rig::is_mouth),
        total(&without, visage_rig::is_mouth)
    );
}
