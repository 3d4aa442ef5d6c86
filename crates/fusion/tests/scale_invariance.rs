//! λ means the same at every resolution, and depth units do not matter (fem::domain).

use faer::Mat;
use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_fem::{FusionSystem, Weights};
use visage_fusion::{FusionSetup, ImagePlaneFuser, MeshingOptions, SurfaceFuser};
use visage_mesh::{Mask, TriangulationKind};

/// Depth of a bumpy surface as a function of normalised image coordinates.
fn z(xn: f64, yn: f64) -> f64 {
    0.6 + 0.03 * (9.0 * xn).sin() * (7.0 * yn).cos()
}

/// Fuses one frame of the surface seen at `scale` × the base resolution (65 × 49, f = 60 px)
/// with mesh spacing `4 · scale` pixels, depth values multiplied by `unit`.
fn fuse(scale: u32, lambda: f64, unit: f64) -> (Vec<[f64; 2]>, Mat<f64>) {
    let (w, h) = (64 * scale + 1, 48 * scale + 1);
    let f = 60.0 * scale as f64;
    let k = Intrinsics::new(w, h, f, f, (w - 1) as f64 / 2.0, (h - 1) as f64 / 2.0).unwrap();
    let mut depth = DepthMap::empty(w, h, DepthKind::Z);
    for v in 0..h {
        for u in 0..w {
            let (xn, yn) = ((u as f64 - k.cx) / f, (v as f64 - k.cy) / f);
            depth.data[(v * w + u) as usize] = (unit * z(xn, yn)) as f32;
        }
    }
    let options = MeshingOptions {
        spacing: 4 * scale,
        triangulation: TriangulationKind::Planar,
        refine_tolerance_m: None,
    };
    let setup = FusionSetup::new(&k, &Mask::filled(w, h, true), &depth, &options).unwrap();
    let normalised = setup
        .mesh
        .points
        .iter()
        .map(|p| [(p[0] - k.cx) / f, (p[1] - k.cy) / f])
        .collect();
    let system = FusionSystem::new(setup.ops.clone(), Weights { lambda, mu: 0.0 }).unwrap();
    let mut fuser = ImagePlaneFuser::new(setup, system, f64::INFINITY);
    fuser.process(&depth).unwrap();
    let x = fuser.solution();
    (normalised, Mat::from_fn(x.len(), 3, |i, c| x[i][c]))
}

fn max_diff(a: &Mat<f64>, b: &Mat<f64>, scale_b: f64) -> f64 {
    let mut m = 0.0f64;
    for c in 0..3 {
        for i in 0..a.nrows() {
            m = m.max((a[(i, c)] - scale_b * b[(i, c)]).abs());
        }
    }
    m
}

fn rms_diff(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
    let mut s = 0.0;
    for c in 0..3 {
        for i in 0..a.nrows() {
            s += (a[(i, c)] - b[(i, c)]).powi(2);
        }
    }
    (s / a.nrows() as f64).sqrt()
}

#[test]
fn lambda_smooths_the_same_at_twice_the_resolution() {
    let lambda = 1e6;
    let (p1, s1) = fuse(1, lambda, 1.0);
    let (p2, s2) = fuse(2, lambda, 1.0);
    assert_eq!(p1.len(), p2.len());
    for (a, b) in p1.iter().zip(&p2) {
        assert!(
            (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12,
            "meshes differ"
        );
    }
    let same = rms_diff(&s1, &s2);
    // What a λ in image pixels would have done: at twice the resolution the same number means
    // 2⁴ = 16 times less smoothing.
    let (_, naive) = fuse(2, lambda / 16.0, 1.0);
    let different = rms_diff(&s1, &naive);
    let (_, unsmoothed) = fuse(1, 1e-9, 1.0);
    let effect = rms_diff(&s1, &unsmoothed);
    assert!(
        effect > 5e-3,
        "λ must visibly smooth this surface (effect {effect} m)"
    );
    eprintln!(
        "RMS: smoothing effect {effect} m, same λ at 2× {same} m, pixel-unit λ {different} m"
    );
    assert!(
        // The residual difference is quadrature: 16 vs 64 pixels per mesh cell in M_D.
        same < 0.1 * effect,
        "same λ at 2× resolution differs by {same} m (smoothing effect {effect} m)"
    );
    assert!(
        different > 5.0 * same,
        "pixel-unit λ ({different} m) should differ far more than {same} m"
    );
}

#[test]
fn depth_units_do_not_change_the_solution() {
    let (_, metres) = fuse(1, 50.0, 1.0);
    let (_, millimetres) = fuse(1, 50.0, 1000.0);
    let diff = max_diff(&metres, &millimetres, 1e-3);
    assert!(diff < 1e-6, "solutions in m and mm differ by {diff} m");
}
