//! Synthesis on the shared ICT-FaceKit subset: seeded, within the configured ranges, and its
//! ground truth consistent (rendered depth lies on the posed mesh; the face mask is the face).

use std::path::PathBuf;

use visage_eval::{synthesize, BenchmarkConfig, SynthesisConfig};
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
