//! Criterion bench of fairing (paper §5) in the per-frame regime: the system and its
//! factorisation built once, then one preconditioned-CG solve per frame (to a relative residual
//! of 1e-10) from the previous frame's result. Mesh: a spherical cap of 1,892 vertices (the default face mesh has 1,833),
//! noisy targets; also the Jacobi preconditioner, and the set-up itself.

use criterion::{criterion_group, criterion_main, Criterion};
use visage_fem::{FairingSystem, Preconditioner};

/// A cap's vertices, triangles and noisy targets.
type Cap = (Vec<[f64; 3]>, Vec<[u32; 3]>, Vec<[f64; 3]>);

/// A 9 cm-radius cap, 60° from the pole, on a 43 × 44 latitude–longitude grid, with a ±0.3 mm
/// ripple along the normals (phase `phase`) as the targets.
fn cap(phase: f64) -> Cap {
    let (rings, segments, r) = (43usize, 44usize, 0.09);
    let mut v = Vec::new();
    let mut noisy = Vec::new();
    for i in 0..rings {
        let theta = (i as f64 + 1.0) / rings as f64 * 60f64.to_radians();
        for j in 0..segments {
            let phi = j as f64 / segments as f64 * std::f64::consts::TAU;
            let n = [
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ];
            v.push(n.map(|c| r * c));
            let ripple = 0.0003 * ((7 * i + 13 * j) as f64 + phase).sin();
            noisy.push(n.map(|c| (r + ripple) * c));
        }
    }
    let mut f = Vec::new();
    for i in 0..rings - 1 {
        for j in 0..segments {
            let a = (i * segments + j) as u32;
            let b = (i * segments + (j + 1) % segments) as u32;
            let (c, d) = (a + segments as u32, b + segments as u32);
            f.push([a, c, b]);
            f.push([b, c, d]);
        }
    }
    (v, f, noisy)
}

fn bench(c: &mut Criterion) {
    let (v, f, noisy) = cap(0.0);
    // The previous frame: other targets (a moved ripple).
    let (_, _, previous) = cap(0.7);
    let weights = vec![1.0; v.len()];
    let gamma = 2e-3f64.powi(-4);
    let mut group = c.benchmark_group("fairing");
    group.bench_function("setup_cholesky_1892", |b| {
        b.iter(|| FairingSystem::new(&v, &f, &weights, gamma, Preconditioner::Cholesky).unwrap())
    });
    for (name, preconditioner) in [
        ("frame_cholesky_1892", Preconditioner::Cholesky),
        ("frame_jacobi_1892", Preconditioner::Jacobi),
    ] {
        let mut system = FairingSystem::new(&v, &f, &weights, gamma, preconditioner).unwrap();
        let (warm, _, _) = system.solve(&previous, &v, 1e-10, 20_000);
        group.bench_function(name, |b| {
            b.iter(|| system.solve(&noisy, &warm, 1e-10, 20_000))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
