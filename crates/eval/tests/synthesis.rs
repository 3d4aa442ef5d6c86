//! Synthesis on the shared ICT-FaceKit subset: seeded, within the configured ranges, and its
//! ground truth consistent (rendered depth lies on the posed mesh; the face mask is the face).

use std::path::PathBuf;

use visage_eval::{
    sequence_sift_anchors, sift_anchors, synthesize, BenchmarkConfig, SiftAnchorOptions,
    SynthesisConfig,
};
use visage_mesh::point_to_mesh::TriangleGrid;
use visage_morphable::IctModel;

/// The ICT-FaceKit subset in `../shared` (tests using it are ignored without it).
#[track_caller]
fn shared_model() -> PathBuf {
    let dir = visage_testdata::shared_dir().join("data/ict-facekit/FaceXModel");
    visage_testdata::require(dir.join("generic_neutral_mesh.obj"));
    dir
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared beside the checkout")]
fn sequences_are_seeded_in_range_and_consistent_with_their_render() {
    let dir = shared_model();
    let model = IctModel::load_with(&dir, &BenchmarkConfig::quick().import).unwrap();
    let config = SynthesisConfig {
        frames: 40,
        ..BenchmarkConfig::quick().synthesis
    };
    let a = synthesize(&model, &config, 5).unwrap();
    let b = synthesize(&model, &config, 5).unwrap();
    let c = synthesize(&model, &config, 6).unwrap();
    assert_eq!(a.frames[39].vertices, b.frames[39].vertices);
    assert_eq!(a.frames[39].depth, b.frames[39].depth);
    assert_ne!(a.frames[0].vertices, c.frames[0].vertices);
    assert!((0.4..=0.8).contains(&a.distance_m));
    for f in &a.frames {
        assert!(f.yaw_deg.abs() <= 25.0 && f.pitch_deg.abs() <= 10.0);
        assert!(f.translation.iter().all(|t| t.abs() <= 0.03));
        assert!(f.expression.iter().all(|w| (0.0..=1.0).contains(w)));
        assert!(f.face.count() > 300, "{}", f.face.count());
    }
    // Face pixels back-project onto the posed mesh (exact renderer, f32 depth) at a plausible
    // distance.
    let f = &a.frames[20];
    let grid = TriangleGrid::new(
        &f.vertices,
        &a.triangles,
        [-0.3, -0.3, 0.1],
        [0.3, 0.3, 1.2],
        0.01,
        0.005,
    );
    let (mut worst, mut n) = (0.0f64, 0);
    for v in 0..a.k.height {
        for u in 0..a.k.width {
            if !f.face.get(u as i64, v as i64) {
                continue;
            }
            let z = f.depth.at(u, v) as f64;
            assert!(z > 0.25 && z < 0.95, "{z}");
            let r = a.k.ray(u as f64, v as f64);
            let p = a.k.backproject(u as f64, v as f64, z / r[2]);
            worst = worst.max(grid.distance(p).unwrap());
            n += 1;
        }
    }
    assert!(n > 300 && worst < 1e-5, "{n} pixels, worst {worst} m");
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared beside the checkout")]
fn head_coordinates_undo_the_pose_and_the_skin_texture_gives_sift_detail() {
    let dir = shared_model();
    let model = IctModel::load_with(&dir, &BenchmarkConfig::quick().import).unwrap();
    let config = SynthesisConfig {
        frames: 30,
        ..BenchmarkConfig::quick().synthesis
    };
    let seq = synthesize(&model, &config, 5).unwrap();
    let (first, last) = (&seq.frames[0], &seq.frames[29]);
    assert!((first.yaw_deg - last.yaw_deg).abs() > 1.0);
    // Vertices off the face do not move with the expression: in head coordinates they stay.
    let (h0, h1) = (seq.head_coordinates(0), seq.head_coordinates(29));
    let still = h0
        .iter()
        .zip(&h1)
        .filter(|(a, b)| (0..3).all(|i| (a[i] - b[i]).abs() < 1e-9))
        .count();
    assert!(still > h0.len() / 4, "{still} of {}", h0.len());

    let untextured = SiftAnchorOptions::default();
    let textured = SiftAnchorOptions {
        textured: true,
        ..untextured
    };
    let plain = sift_anchors(&seq, 0, &untextured).unwrap();
    let detailed = sift_anchors(&seq, 0, &textured).unwrap();
    assert!(
        detailed.len() > 2 * plain.len(),
        "{} keypoints textured, {} plain",
        detailed.len(),
        plain.len()
    );
    assert_eq!(detailed, sift_anchors(&seq, 0, &textured).unwrap());
    let (union, frames) = sequence_sift_anchors(
        &seq,
        &SiftAnchorOptions {
            frame_step: Some(10),
            ..textured
        },
    )
    .unwrap();
    assert_eq!(frames, 3);
    assert_eq!(union[..detailed.len()], detailed[..]);
    assert!(union.len() > detailed.len());
}
