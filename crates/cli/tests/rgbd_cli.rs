//! `visage run --rgbd` on a TUM RGB-D recording made from the ground-truth benchmark: colour
//! renders of a synthetic ICT-FaceKit face with a skin texture, its depth with CNN-like noise
//! (holes, flying pixels at the silhouette, low-frequency error) as 16-bit PNGs at 5000 per
//! metre, timestamps that jitter by ±3 ms and a depth clock 4 ms behind, one depth frame
//! dropped. Over three such recordings (one sequence's draw alone is not representative), the
//! fused meshes must beat the raw depth on the same mesh on error against the truth and on
//! jitter.

mod common;

use common::{s, visage};

use serde_json::Value;
use visage_eval::{
    sequence_skin_albedo, synthesize, write_tum_recording, NoiseGenerator, NoiseModel,
    RecordingClock, SynthesisConfig,
};
use visage_mesh::point_to_mesh::TriangleGrid;
use visage_morphable::{IctModel, ImportOptions};

/// Σ squared distance (m²) of the PLY meshes `dir/NNNNNN.ply` of frames `meshed` from the
/// truth of their frames, and the vertex count.
fn squared_error(
    dir: &std::path::Path,
    seq: &visage_eval::SyntheticSequence,
    meshed: &[usize],
) -> (f64, usize) {
    let (mut sum, mut n) = (0.0, 0usize);
    for &k in meshed {
        let mesh = visage_mesh::io::read_ply(&dir.join(format!("{k:06}.ply"))).unwrap();
        let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
        for v in &mesh.vertices {
            for c in 0..3 {
                lo[c] = lo[c].min(v[c]);
                hi[c] = hi[c].max(v[c]);
            }
        }
        let truth = &seq.frames[k].vertices;
        let grid = TriangleGrid::new(truth, &seq.triangles, lo, hi, 0.05, 0.005);
        for v in &mesh.vertices {
            if let Some(d) = grid.distance(*v) {
                sum += d * d;
                n += 1;
            }
        }
    }
    (sum, n)
}

/// What a recording's run gave: Σ e² and count for the fused and the raw surface, and the
/// rigid-motion-removed vertex jitter (mm/frame) of both.
struct Scores {
    fused: (f64, usize),
    raw: (f64, usize),
    jitter: (f64, f64),
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn tum_recordings_of_synthetic_faces_run_and_beat_their_raw_depth() {
    let models = visage_testdata::models_dir();
    for file in visage_testdata::MODEL_FILES {
        visage_testdata::require(models.join(file));
    }
    let ict =
        visage_testdata::require(visage_testdata::shared_dir().join("data/ict-facekit/FaceXModel"));
    let model = IctModel::load_with(
        &ict,
        &ImportOptions {
            max_identities: Some(10),
            expressions: Some(
                ["jawOpen", "mouthSmile_L", "eyeBlink_R", "browInnerUp_L"]
                    .map(String::from)
                    .to_vec(),
            ),
        },
    )
    .unwrap();
    let scores: Vec<Scores> = (1..=3)
        .map(|seed| run_recording(&model, &models, seed))
        .collect();
    let rmse = |pick: fn(&Scores) -> (f64, usize)| {
        let (sum, n) = scores
            .iter()
            .map(pick)
            .fold((0.0, 0), |(s, n), (a, b)| (s + a, n + b));
        1e3 * (sum / n as f64).sqrt()
    };
    let (fused, raw) = (rmse(|s| s.fused), rmse(|s| s.raw));
    let jf = scores.iter().map(|s| s.jitter.0).sum::<f64>() / 3.0;
    let jr = scores.iter().map(|s| s.jitter.1).sum::<f64>() / 3.0;
    eprintln!("RMSE fused {fused:.3} mm, raw {raw:.3} mm; jitter fused {jf:.3}, raw {jr:.3}");
    assert!(fused < raw, "RMSE: fused {fused:.3} mm, raw {raw:.3} mm");
    assert!(jf < jr, "jitter: fused {jf:.3} mm, raw {jr:.3} mm");
}

/// Synthesises sequence `seed`, writes it as a TUM recording and runs `visage run --rgbd`.
fn run_recording(model: &IctModel, models: &std::path::Path, seed: u64) -> Scores {
    // A Kinect-like camera: 640×480, f = 525 px; the face 0.5–0.7 m away.
    let config = SynthesisConfig {
        width: 640,
        height: 480,
        focal_px: 525.0,
        frames: 30,
        distance_m: (0.5, 0.7),
        ..SynthesisConfig::default()
    };
    let seq = synthesize(model, &config, seed).unwrap();
    let mut noise = NoiseGenerator::new(NoiseModel::cnn_like(), seed + 100).unwrap();
    let depth: Vec<_> = seq.frames.iter().map(|f| noise.apply(&f.depth)).collect();
    let tmp = tempfile::tempdir().unwrap();
    let rec = tmp.path().join("recording");
    let clock = RecordingClock {
        dropped_depth: vec![17],
        ..RecordingClock::default()
    };
    let albedo = sequence_skin_albedo(&seq, seed + 200);
    write_tum_recording(&seq, &albedo, &depth, &clock, &rec, seed + 300).unwrap();
    let camera = tmp.path().join("camera.json");
    seq.k.save_json(&camera).unwrap();
    let out = tmp.path().join("out");
    let o = visage(&[
        "run",
        "--rgbd",
        s(&rec),
        "--intrinsics",
        s(&camera),
        "--out",
        s(&out),
        "--ply",
        "--save-raw",
        "--models",
        s(models),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("TUM RGB-D recording, 30 colour frames, 29 with a depth map"),
        "{stderr}"
    );
    let metrics: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    let frames = metrics["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 30);
    // The tracker finds the rendered face in (nearly) every frame; the frame without depth
    // carries the surface; the timestamps are the recording's.
    let meshed: Vec<usize> = (0..frames.len())
        .filter(|&k| frames[k]["status"] == "solved" || frames[k]["status"] == "carried")
        .collect();
    assert!(meshed.len() >= 27, "{} of 30 frames meshed", meshed.len());
    if frames[17]["status"] != "no_face" {
        assert_eq!(frames[17]["status"], "carried", "{}", frames[17]);
    }
    let t1 = frames[1]["time_s"].as_f64().unwrap();
    assert!((t1 - 1.0 / 30.0).abs() < 0.007 && t1 != 1.0 / 30.0, "{t1}");
    let jitter = &metrics["summary"]["quality"]["vertex_jitter_mm"];
    let scores = Scores {
        fused: squared_error(&out.join("meshes"), &seq, &meshed),
        raw: squared_error(&out.join("raw"), &seq, &meshed),
        jitter: (
            jitter["fused"].as_f64().unwrap(),
            jitter["raw"].as_f64().unwrap(),
        ),
    };
    let mm = |(s, n): (f64, usize)| 1e3 * (s / n as f64).sqrt();
    eprintln!(
        "sequence {seed} ({} frames meshed): RMSE fused {:.3} mm, raw {:.3} mm; jitter fused {:.3}, raw {:.3}",
        meshed.len(),
        mm(scores.fused),
        mm(scores.raw),
        scores.jitter.0,
        scores.jitter.1
    );
    scores
}
