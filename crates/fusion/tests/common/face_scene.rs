//! A synthetic "face" for the face-anchored fusion tests: a curved template grid in head
//! coordinates, a camera, and head poses.

use visage_camera::{Intrinsics, RigidTransform};
use visage_fusion::{AnchoredFuser, FaceDomain};

/// Grid points per side of the template.
pub const SIDE: usize = 9;
/// Half-width of the template, metres.
pub const HALF: f64 = 0.07;

/// The template: a spherical cap facing −z (towards the camera), metres, head coordinates;
/// `curved = false` gives the flat square.
pub fn template(curved: bool) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    for j in 0..SIDE {
        for i in 0..SIDE {
            let x = -HALF + 2.0 * HALF * i as f64 / (SIDE - 1) as f64;
            let y = -HALF + 2.0 * HALF * j as f64 / (SIDE - 1) as f64;
            let z = if curved {
                0.12 - (0.12f64.powi(2) - x * x - y * y).sqrt()
            } else {
                0.0
            };
            v.push([x, y, z]);
        }
    }
    let mut t = Vec::new();
    for j in 0..SIDE - 1 {
        for i in 0..SIDE - 1 {
            let a = (j * SIDE + i) as u32;
            let (b, c, d) = (a + 1, a + SIDE as u32, a + SIDE as u32 + 1);
            t.push([a, c, b]);
            t.push([b, c, d]);
        }
    }
    (v, t)
}

pub fn camera() -> Intrinsics {
    Intrinsics::new(640, 480, 500.0, 500.0, 319.5, 239.5).unwrap()
}

/// Head pose: yaw `yaw` radians about the head's vertical axis, 0.5 m in front of the camera,
/// shifted sideways by `shift` metres.
pub fn pose(yaw: f64, shift: f64) -> RigidTransform {
    let (c, s) = (yaw.cos(), yaw.sin());
    RigidTransform {
        rotation: [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
        translation: [shift, 0.01, 0.5],
    }
}

/// A smooth, fixed "expression": the template pushed along z by a bump, metres.
pub fn expression(p: [f64; 3]) -> [f64; 3] {
    let r2 = (p[0] * p[0] + p[1] * p[1]) / (HALF * HALF);
    [p[0], p[1], p[2] - 0.006 * (-2.0 * r2).exp()]
}

/// The fuser on the template with `factor`-fold subdivision.
pub fn fuser(
    template: &[[f64; 3]],
    triangles: &[[u32; 3]],
    factor: usize,
    lambda: f64,
    mu: f64,
) -> AnchoredFuser {
    let domain = FaceDomain::subdivide(template.len(), triangles, factor).unwrap();
    AnchoredFuser::new(
        domain,
        template,
        camera(),
        visage_fem::Weights { lambda, mu },
        10.0,
    )
    .unwrap()
}

/// The surface points and landmark pixels of `points` (head coordinates) seen with `pose`.
pub fn observe(points: &[[f64; 3]], pose: &RigidTransform) -> (Vec<[f64; 3]>, Vec<[f64; 2]>) {
    let k = camera();
    let cam: Vec<[f64; 3]> = points.iter().map(|&p| pose.apply(p)).collect();
    let px = cam.iter().map(|&p| k.project(p)).collect();
    (cam, px)
}
