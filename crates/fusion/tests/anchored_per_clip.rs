//! The face-anchored fusion factors its matrices once per clip — head motion changes only the
//! right-hand side — and a streaming frame allocates nothing. One test in its own binary: the
//! factorisation count is process-wide.

#[path = "common/counting_allocator.rs"]
mod counting_allocator;

#[path = "common/face_scene.rs"]
mod face_scene;

use counting_allocator::allocations;
use face_scene::{expression, fuser, observe, pose, template};
use visage_fem::Factorization;
use visage_fusion::{AnchoredFrame, FrameDepth, FrameStatus, SurfaceFuser};

#[test]
fn one_factorisation_per_clip_and_no_allocation_per_frame() {
    let (v, t) = template(true);
    let face: Vec<[f64; 3]> = v.iter().map(|&p| expression(p)).collect();
    let before = Factorization::numeric_count();
    let mut f = fuser(&v, &t, 2, 10.0, 0.5);
    // The streaming matrix (1+μ)M + λK and the reset matrix M + λK.
    assert_eq!(Factorization::numeric_count() - before, 2);
    let frames: Vec<_> = (0..30)
        .map(|k| {
            let p = pose(0.3 * (k as f64 * 0.3).sin(), 0.01 * (k as f64 * 0.2).cos());
            let (surface, px) = observe(&face, &p);
            (p, surface, px)
        })
        .collect();
    let factored = Factorization::numeric_count();
    let mut allocations_after_first = 0;
    for (k, (p, surface, px)) in frames.iter().enumerate() {
        let start = allocations();
        let r = f
            .process(&AnchoredFrame {
                template: None,
                landmarks_px: px,
                pose: *p,
                depth: FrameDepth::Surface(surface),
            })
            .unwrap();
        let quality = f.frame_quality();
        assert_eq!(r.status, FrameStatus::Solved);
        assert!(quality.1.mean_abs_h.is_finite());
        if k > 0 {
            allocations_after_first += allocations() - start;
        }
    }
    assert_eq!(
        Factorization::numeric_count(),
        factored,
        "a frame refactored"
    );
    assert_eq!(allocations_after_first, 0);
}
