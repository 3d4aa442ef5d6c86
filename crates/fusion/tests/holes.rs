//! Missing depth neither changes the factored matrix nor pulls the surface toward the camera.

use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_fem::{FusionSystem, Weights};
use visage_fusion::{FrameStatus, FusionSetup, ImagePlaneFuser, MeshingOptions, SurfaceFuser};
use visage_mesh::Mask;

const W: u32 = 64;
const H: u32 = 48;

fn z_true(u: f64, v: f64) -> f64 {
    0.7 + 0.05 * (u / 20.0).sin() * (v / 15.0).cos()
}

fn frame(hole: impl Fn(u32, u32) -> bool) -> DepthMap {
    let mut d = DepthMap::empty(W, H, DepthKind::Z);
    for v in 0..H {
        for u in 0..W {
            let i = (v * W + u) as usize;
            d.data[i] = if hole(u, v) {
                0.0
            } else {
                z_true(u as f64, v as f64) as f32
            };
        }
    }
    d
}

fn in_hole(u: f64, v: f64) -> bool {
    (u - 32.0).powi(2) + (v - 24.0).powi(2) < 100.0
}

/// Largest |z − z_true| over the vertices inside the hole.
fn hole_error(fuser: &ImagePlaneFuser) -> f64 {
    let (k, x) = (fuser.setup().k, fuser.solution());
    let mut worst = 0.0f64;
    for (i, p) in fuser.setup().mesh.points.iter().enumerate() {
        if in_hole(p[0], p[1]) {
            let z = x[i][2];
            let proj = k.project(x[i]);
            worst = worst.max((z - z_true(proj[0], proj[1])).abs());
        }
    }
    worst
}

fn fuser(first: &DepthMap) -> ImagePlaneFuser {
    let k = Intrinsics::from_fov(W, H, 60.0).unwrap();
    let setup = FusionSetup::new(
        &k,
        &Mask::filled(W, H, true),
        first,
        &MeshingOptions::default(),
    )
    .unwrap();
    let system = FusionSystem::new(setup.ops.clone(), Weights::default()).unwrap();
    ImagePlaneFuser::new(setup, system, 10.0)
}

#[test]
fn a_hole_keeps_the_previous_surface() {
    let full = frame(|_, _| false);
    let mut f = fuser(&full);
    f.process(&full).unwrap();
    let holed = frame(|u, v| in_hole(u as f64, v as f64));
    for _ in 0..3 {
        let r = f.process(&holed).unwrap();
        assert_eq!(r.status, FrameStatus::Solved);
        assert!(r.valid_fraction < 0.99);
    }
    let err = hole_error(&f);
    assert!(err < 2e-3, "surface in the hole moved by {err} m");
}

#[test]
fn a_hole_in_the_first_frame_is_inpainted_not_zeroed() {
    let holed = frame(|u, v| in_hole(u as f64, v as f64));
    let mut f = fuser(&holed);
    assert_eq!(f.process(&holed).unwrap().status, FrameStatus::Solved);
    let err = hole_error(&f);
    assert!(
        err < 0.02,
        "in-painted hole is {err} m off (a zero pull would be ~0.7 m)"
    );
}

#[test]
fn a_frame_without_depth_is_carried_over_exactly() {
    let full = frame(|_, _| false);
    let mut f = fuser(&full);
    f.process(&full).unwrap();
    let before = f.solution().to_owned();
    let r = f.process(&frame(|_, _| true)).unwrap();
    assert_eq!(r.status, FrameStatus::Carried);
    assert_eq!(f.solution().to_owned(), before);
    // A first frame without any depth has nothing to carry.
    let mut g = fuser(&full);
    assert_eq!(
        g.process(&frame(|_, _| true)).unwrap().status,
        FrameStatus::NoData
    );
}
