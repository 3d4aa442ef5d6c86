//! Criterion benches of the factor-once solver (paper §4): factorisation and per-frame solve
//! with 3 right-hand-side columns, at ~10k and ~20k vertices on a 4-pixel grid.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use faer::Mat;
use visage_camera::Intrinsics;
use visage_fem::domain::domain_coordinates;
use visage_fem::{
    biharmonic, cotan_laplacian, lumped_mass, mass_matrix, Factorization, FusionSystem, Operators,
    PixelQuadrature, StreamingSolver, Weights,
};
use visage_mesh::{sample_domain, Mask, PlanarMesh, SamplingOptions};

fn system(vertices: usize) -> FusionSystem {
    let cols = ((vertices as f64 * 4.0 / 3.0).sqrt()).round() as u32;
    let rows = (vertices as f64 / cols as f64).round() as u32;
    let (w, h) = (4 * (cols - 1) + 1, 4 * (rows - 1) + 1);
    let k = Intrinsics::from_fov(w, h, 60.0).expect("valid camera");
    let opts = SamplingOptions {
        spacing: 4,
        refine_tolerance: None,
        ..Default::default()
    };
    let samples = sample_domain(&Mask::filled(w, h, true), None, &opts).expect("samples");
    let mesh = PlanarMesh::triangulate(&samples).expect("mesh");
    let xi = domain_coordinates(&mesh.points, &k);
    let l = cotan_laplacian(&xi, &mesh.triangles).expect("L");
    let ml = lumped_mass(&xi, &mesh.triangles).expect("M_l");
    let ops = Operators {
        mass: mass_matrix(&xi, &mesh.triangles).expect("M"),
        data_mass: PixelQuadrature::new(&mesh.points, &mesh.triangles, &k)
            .mass_matrix()
            .expect("M_D"),
        biharmonic: biharmonic(&l, &ml).expect("K"),
    };
    FusionSystem::new(ops, Weights::default()).expect("SPD")
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("solver");
    group.sample_size(20);
    for n in [10_000, 20_000] {
        let sys = system(n);
        let a = sys.matrix_temporal().clone();
        group.bench_with_input(BenchmarkId::new("factor", n), &a, |b, a| {
            b.iter(|| Factorization::new(a).expect("SPD"))
        });
        let nv = sys.dim();
        let rhs = Mat::from_fn(nv, 3, |i, c| 0.5 + 0.001 * ((i * 7 + c) % 13) as f64);
        let mut factor = Factorization::new(&a).expect("SPD");
        let mut x = rhs.clone();
        group.bench_function(BenchmarkId::new("solve_3_columns", n), |b| {
            b.iter(|| {
                x.copy_from(&rhs);
                factor.solve_in_place(x.as_mut());
            })
        });
        let mut solver = StreamingSolver::new(sys);
        let mut out = Mat::zeros(nv, 3);
        solver.step(rhs.as_ref(), out.as_mut());
        group.bench_function(BenchmarkId::new("streaming_step", n), |b| {
            b.iter(|| solver.step(rhs.as_ref(), out.as_mut()))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
