//! The keypoint check of the head's motion on a real clip: SIFT on the face, matched frame to
//! frame and lifted onto the fitted surface, moves with the landmark pose.

use visage::{Input, Reconstructor};

fn clip() -> std::path::PathBuf {
    visage_testdata::require(visage_testdata::shared_dir().join("data/video/lp_d18.mp4"))
}

const FRAMES: usize = 40;

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn keypoints_move_with_the_landmark_pose() {
    let input = Input::open(&clip()).unwrap().max_frames(FRAMES).unwrap();
    let mut sink = ();
    let outcome = Reconstructor::builder()
        .models_dir(visage_testdata::models_dir())
        .keypoint_motion(true)
        .build_for(&input)
        .unwrap()
        .run(input, &mut sink);
    assert!(outcome.error.is_none());
    let s = outcome
        .summary
        .keypoint_motion
        .expect("a summary with keypoints on");
    let ms = &outcome.summary.stages["keypoints"];
    eprintln!("{s:?} {ms:?}");
    // Every frame but the first is compared with its predecessor.
    assert_eq!(s.frames, FRAMES - 1);
    assert!(s.estimated as f64 >= 0.9 * s.frames as f64, "{s:?}");
    assert!(s.median_matches >= 10.0 && s.median_inliers >= 8.0, "{s:?}");
    assert!(s.median_rotation_disagreement_deg < 1.0, "{s:?}");
    assert!(s.median_translation_disagreement_mm < 3.0, "{s:?}");
    let first = &outcome.frames[0];
    assert!(
        first.keypoint_motion.is_none(),
        "nothing to compare the first frame with"
    );
    assert!(outcome.frames[1..].iter().all(|f| f.ms.keypoints > 0.0));
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn one_thread_and_the_staged_run_check_alike() {
    const N: usize = 8;
    let builder = || {
        Reconstructor::builder()
            .models_dir(visage_testdata::models_dir())
            .keypoint_motion(true)
            .latency(0)
    };
    let input = Input::open(&clip()).unwrap().max_frames(N).unwrap();
    let mut single = builder().build_for(&input).unwrap();
    let mut by_process = Vec::new();
    for frame in input {
        let r = single.process(&frame.unwrap()).unwrap();
        by_process.push(r.metrics.keypoint_motion);
    }
    let input = Input::open(&clip()).unwrap().max_frames(N).unwrap();
    let outcome = builder().build_for(&input).unwrap().run(input, &mut ());
    let by_run: Vec<_> = outcome.frames.iter().map(|f| f.keypoint_motion).collect();
    assert_eq!(by_process, by_run);
    assert!(by_run[1..].iter().all(Option::is_some));
}
