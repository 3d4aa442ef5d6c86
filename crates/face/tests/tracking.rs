//! Video tracking on the project's clips: the face is tracked in every frame and the detector
//! runs on a small fraction of them.

mod common;

use visage_face::{FaceMesh, FaceTracker};
use visage_video::FrameSource;

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn both_clips_are_tracked_in_every_frame() {
    let (data, models) = (common::data_dir(), common::models_dir());
    for clip in ["lp_d13.mp4", "lp_d18.mp4"] {
        let mut tracker = FaceTracker::new(FaceMesh::load(&models).unwrap());
        let mut missing = Vec::new();
        for frame in FrameSource::open(&data.join("video").join(clip)).unwrap() {
            let frame = frame.unwrap();
            let step = tracker.track(&frame.image).unwrap();
            match step.face {
                Some(face) => assert_eq!(face.landmarks.points.len(), 468),
                None => missing.push(frame.index),
            }
        }
        let fraction = tracker.detector_runs as f64 / tracker.frames as f64;
        println!(
            "{clip}: {} frames, detector ran on {} ({:.1}%), lost on {:?}",
            tracker.frames,
            tracker.detector_runs,
            100.0 * fraction,
            missing
        );
        assert!(tracker.frames > 100);
        assert!(
            missing.is_empty(),
            "{clip}: face lost on frames {missing:?}"
        );
        assert!(
            fraction < 0.05,
            "{clip}: detector ran on {:.1}% of frames",
            100.0 * fraction
        );
    }
}
