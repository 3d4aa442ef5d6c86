//! The temporal model on real frames: a clip cut together from two shots (with FFmpeg) is cut
//! where the second shot starts, and that frame's mesh is the one a fresh run of the second
//! shot gives; the smoother hands every frame over once, in order, steadier than tracked.

use std::path::Path;
use std::process::Command;

use visage::{Error, FrameMetrics, FrameSink, Input, LandmarksFrame, MeshFrame, Reconstructor};

const SHOT: usize = 12;

fn builder() -> visage::Builder {
    Reconstructor::builder().models_dir(visage_testdata::models_dir())
}

/// Extracts the first `SHOT` frames of `clip` (through `filter`) into `dir` as PNGs named
/// `prefix_NNN.png`.
fn extract(clip: &Path, filter: &str, dir: &Path, prefix: &str) {
    let pattern = dir.join(format!("{prefix}_%03d.png"));
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(clip)
        .args(["-vf", filter, "-frames:v", &SHOT.to_string()])
        .arg(&pattern)
        .status()
        .expect("FFmpeg runs");
    assert!(status.success(), "FFmpeg failed on {}", clip.display());
}

/// A frame's 468 points, pixels.
type Points = Vec<[f64; 2]>;

#[derive(Default)]
struct Collect {
    meshes: Vec<(usize, Vec<[f64; 3]>)>,
    cuts: Vec<usize>,
    /// Tracked and fused landmarks per frame.
    landmarks: Vec<(Points, Points)>,
}

impl FrameSink for Collect {
    fn mesh(&mut self, frame: &MeshFrame<'_>) -> Result<(), Error> {
        self.meshes
            .push((frame.index, frame.surfaces.fused.clone()));
        Ok(())
    }

    fn landmarks(&mut self, record: &LandmarksFrame) -> Result<(), Error> {
        let face = &record.faces[0];
        let tracked = face.landmarks.iter().map(|p| [p[0], p[1]]).collect();
        self.landmarks
            .push((tracked, face.fused_landmarks.clone().unwrap()));
        Ok(())
    }

    fn frame_done(&mut self, m: &FrameMetrics) {
        if m.cut {
            self.cuts.push(m.index);
        }
    }
}

fn run(dir: &Path) -> Collect {
    let input = Input::open(dir).unwrap();
    let mut sink = Collect::default();
    let outcome = builder().build_for(&input).unwrap().run(input, &mut sink);
    assert!(outcome.error.is_none(), "{:?}", outcome.error);
    assert_eq!(outcome.summary.cuts, sink.cuts);
    sink
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_cut_restarts_the_temporal_model_as_a_fresh_run() {
    let video = visage_testdata::shared_dir().join("data/video");
    let tmp = tempfile::tempdir().unwrap();
    let (both, second) = (tmp.path().join("both"), tmp.path().join("second"));
    std::fs::create_dir_all(&both).unwrap();
    std::fs::create_dir_all(&second).unwrap();
    // Two shots of different people, the second cropped square to the first one's size.
    extract(&video.join("lp_d18.mp4"), "null", &both, "a");
    let square = "crop=720:720:0:280,scale=480:480";
    extract(&video.join("lp_d13.mp4"), square, &both, "b");
    extract(&video.join("lp_d13.mp4"), square, &second, "b");

    let cut = run(&both);
    assert_eq!(
        cut.cuts,
        vec![SHOT],
        "the cut, and nothing else, is detected"
    );
    let indices: Vec<usize> = cut.meshes.iter().map(|m| m.0).collect();
    assert_eq!(indices, (0..2 * SHOT).collect::<Vec<_>>());
    let fresh = run(&second);
    assert!(fresh.cuts.is_empty());
    let distance = cut.meshes[SHOT]
        .1
        .iter()
        .zip(&fresh.meshes[0].1)
        .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt())
        .fold(0.0f64, f64::max);
    assert!(
        distance <= 1e-4,
        "the first frame after the cut is {distance} m from a fresh solve"
    );
    // Within the second shot the temporal model smooths: the fused landmarks are steadier
    // than the tracked ones.
    let jitter = |fused: bool| {
        let pick = |t: usize| {
            let (tracked, f) = &cut.landmarks[t];
            if fused {
                f
            } else {
                tracked
            }
        };
        let mut sum = 0.0;
        for t in SHOT + 1..2 * SHOT - 1 {
            for i in 0..468 {
                for c in 0..2 {
                    let d = pick(t + 1)[i][c] - 2.0 * pick(t)[i][c] + pick(t - 1)[i][c];
                    sum += d * d;
                }
            }
        }
        sum
    };
    let (tracked, fused) = (jitter(false), jitter(true));
    assert!(
        fused < 0.5 * tracked,
        "jitter² {fused} vs tracked {tracked}"
    );
}

/// Two people filmed alike — each face cropped to the same place on the same grey
/// background, so that the whole picture barely changes — is a cut where the second starts:
/// the face itself changed. The picture alone does not tell (checked), the face does.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn another_person_filmed_alike_is_a_cut() {
    let video = visage_testdata::shared_dir().join("data/video");
    let tmp = tempfile::tempdir().unwrap();
    let both = tmp.path().join("both");
    std::fs::create_dir_all(&both).unwrap();
    let place = "scale=300:300,pad=640:480:170:90:gray";
    extract(
        &video.join("lp_d18.mp4"),
        &format!("crop=330:330:81:120,{place}"),
        &both,
        "a",
    );
    extract(
        &video.join("lp_d13.mp4"),
        &format!("crop=550:550:93:362,{place}"),
        &both,
        "b",
    );
    let frame = |name: &str| image::open(both.join(name)).unwrap().to_rgb8();
    let mut picture = visage_face::CutDetector::default();
    assert!(!picture.picture_cut(&frame(&format!("a_{SHOT:03}.png"))));
    assert!(
        !picture.picture_cut(&frame("b_001.png")),
        "the pictures alone differ too little for a cut"
    );
    let cut = run(&both);
    assert_eq!(
        cut.cuts,
        vec![SHOT],
        "the change of person, and nothing else"
    );
}
