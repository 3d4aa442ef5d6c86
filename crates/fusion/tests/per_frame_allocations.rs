//! The per-frame hot path (sampling, hole filling, right-hand side, solve, residual, metrics)
//! allocates nothing once a predecessor exists. Counted with a wrapping global allocator.

#[path = "common/counting_allocator.rs"]
mod counting_allocator;

use counting_allocator::allocations;
use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_fem::{FusionSystem, Weights};
use visage_fusion::{FrameStatus, FusionSetup, ImagePlaneFuser, MeshingOptions, SurfaceFuser};
use visage_mesh::Mask;

#[test]
fn streaming_frames_allocate_nothing() {
    let (w, h) = (64u32, 48u32);
    let k = Intrinsics::from_fov(w, h, 60.0).unwrap();
    let frame = |t: f64| {
        let mut d = DepthMap::empty(w, h, DepthKind::Z);
        for v in 0..h {
            for u in 0..w {
                let hole = (u as f64 - 20.0 - 5.0 * t).powi(2) + (v as f64 - 24.0).powi(2) < 30.0;
                if !hole {
                    d.data[(v * w + u) as usize] = (0.6 + 0.03 * (u as f64 * 0.1 + t).sin()) as f32;
                }
            }
        }
        d
    };
    // The counter sees allocations at all.
    let before = allocations();
    let probe = std::hint::black_box(vec![0u8; 64]);
    assert!(allocations() > before && probe.len() == 64);
    let first = frame(0.0);
    let setup = FusionSetup::new(
        &k,
        &Mask::filled(w, h, true),
        &first,
        &MeshingOptions::default(),
    )
    .unwrap();
    let system = FusionSystem::new(setup.ops.clone(), Weights::default()).unwrap();
    let mut fuser = ImagePlaneFuser::new(setup, system, 10.0);
    assert_eq!(fuser.process(&first).unwrap().status, FrameStatus::Solved);
    let frames: Vec<DepthMap> = (1..5).map(|t| frame(t as f64)).collect();
    for depth in &frames {
        let before = allocations();
        let r = fuser.process(depth).unwrap();
        let quality = fuser.frame_quality();
        let after = allocations();
        assert_eq!(r.status, FrameStatus::Solved);
        assert!(r.relative_residual < 1e-10 && quality.1.mean_abs_h > 0.0);
        assert_eq!(
            after - before,
            0,
            "a streaming frame allocated {} times",
            after - before
        );
    }
}
