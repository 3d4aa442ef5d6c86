//! Properties of the P1 operators on a corpus of meshes, at several scales of the domain.

use faer::Mat;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use visage_fem::sparse::{entry, for_each_entry, sym_matmul, SparseMatrix};
use visage_fem::{biharmonic, cotan_laplacian, lumped_mass, mass_matrix};
use visage_mesh::{sample_domain, Mask, PlanarMesh, SamplingOptions};

fn corpus() -> Vec<(String, PlanarMesh)> {
    let mut out = Vec::new();
    let disc = {
        let mut m = Mask::filled(40, 36, false);
        for v in 0..36u32 {
            for u in 0..40u32 {
                m.data[(v * 40 + u) as usize] =
                    (u as f64 - 20.0).powi(2) + (v as f64 - 18.0).powi(2) < 15.0 * 15.0;
            }
        }
        m
    };
    for (name, mask, spacing) in [("rect", Mask::filled(21, 17, true), 4), ("disc", disc, 3)] {
        let s = sample_domain(
            &mask,
            None,
            &SamplingOptions {
                spacing,
                ..Default::default()
            },
        )
        .unwrap();
        out.push((name.to_string(), PlanarMesh::triangulate(&s).unwrap()));
    }
    // An irregular mesh: jittered interior points.
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let s = sample_domain(
        &Mask::filled(30, 30, true),
        None,
        &SamplingOptions {
            spacing: 5,
            ..Default::default()
        },
    )
    .unwrap();
    let mut mesh = PlanarMesh::triangulate(&s).unwrap();
    let boundary = mesh.boundary_vertices();
    for (p, b) in mesh.points.iter_mut().zip(&boundary) {
        if !b {
            p[0] += rng.random_range(-1.0..1.0);
            p[1] += rng.random_range(-1.0..1.0);
        }
    }
    out.push(("jittered".to_string(), mesh));
    out
}

fn scaled(points: &[[f64; 2]], s: f64) -> Vec<[f64; 2]> {
    points.iter().map(|p| [p[0] * s, p[1] * s]).collect()
}

fn max_abs(a: &SparseMatrix) -> f64 {
    let mut m = 0.0f64;
    for_each_entry(a, |_, _, v| m = m.max(v.abs()));
    m
}

fn assert_symmetric(name: &str, a: &SparseMatrix) {
    let tol = 1e-12 * max_abs(a);
    for_each_entry(a, |i, j, v| {
        assert!(
            (v - entry(a, j, i)).abs() <= tol,
            "{name}: ({i},{j}) = {v} vs {}",
            entry(a, j, i)
        );
    });
}

fn apply(a: &SparseMatrix, f: &[f64]) -> Vec<f64> {
    let x = Mat::from_fn(f.len(), 1, |i, _| f[i]);
    let mut y = Mat::zeros(f.len(), 1);
    sym_matmul(a, x.as_ref(), 1.0, 0.0, y.as_mut());
    (0..f.len()).map(|i| y[(i, 0)]).collect()
}

fn dense(a: &SparseMatrix) -> Mat<f64> {
    let mut d = Mat::zeros(a.nrows(), a.ncols());
    for_each_entry(a, |i, j, v| d[(i, j)] += v);
    d
}

#[test]
fn laplacian_mass_and_biharmonic_properties_hold_at_every_scale() {
    for (name, mesh) in corpus() {
        let boundary = mesh.boundary_vertices();
        for scale in [1.0, 1e-4, 1e4] {
            let name = format!("{name} ×{scale:e}");
            let p = scaled(&mesh.points, scale);
            let n = p.len();
            let l = cotan_laplacian(&p, &mesh.triangles).unwrap();
            let m = mass_matrix(&p, &mesh.triangles).unwrap();
            let ml = lumped_mass(&p, &mesh.triangles).unwrap();
            let k = biharmonic(&l, &ml).unwrap();

            // L: symmetric, zero row sums, exact on linear functions at interior vertices.
            assert_symmetric(&format!("{name} L"), &l);
            let lmax = max_abs(&l);
            let ones = vec![1.0; n];
            assert!(
                apply(&l, &ones).iter().all(|r| r.abs() <= 1e-12 * lmax),
                "{name}: L rows must sum to 0"
            );
            let linear: Vec<f64> = p
                .iter()
                .map(|q| 0.3 * q[0] - 1.7 * q[1] + 2.0 * scale)
                .collect();
            let fmax = linear.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let lf = apply(&l, &linear);
            for i in (0..n).filter(|&i| !boundary[i]) {
                assert!(
                    lf[i].abs() <= 1e-10 * lmax * fmax,
                    "{name}: (L f)_{i} = {} for linear f",
                    lf[i]
                );
            }
            assert!(
                lf.iter().any(|v| v.abs() > 1e-6 * lmax * fmax),
                "{name}: boundary flux of a linear f must show"
            );

            // M: symmetric, sums to the area; lumped mass likewise.
            assert_symmetric(&format!("{name} M"), &m);
            let area = mesh.area() * scale * scale;
            let mut total = 0.0;
            for_each_entry(&m, |_, _, v| total += v);
            assert!(
                (total - area).abs() <= 1e-10 * area,
                "{name}: ΣM = {total}, area {area}"
            );
            assert!((ml.iter().sum::<f64>() - area).abs() <= 1e-10 * area);

            // K: symmetric positive semi-definite with exactly the constants as null space.
            assert_symmetric(&format!("{name} K"), &k);
            let kmax = max_abs(&k);
            assert!(
                apply(&k, &ones).iter().all(|r| r.abs() <= 1e-10 * kmax),
                "{name}: K·1 ≠ 0"
            );
            let kd = dense(&k);
            let mut with_constants = kd.clone();
            // K + c·11ᵀ is positive definite iff null(K) = span{1} (K is PSD).
            let c = kmax / n as f64;
            for i in 0..n {
                for j in 0..n {
                    with_constants[(i, j)] += c;
                }
            }
            assert!(
                with_constants.llt(faer::Side::Lower).is_ok(),
                "{name}: K has a null space beyond constants"
            );
            let eigen = kd.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
            let lowest = eigen.iter().cloned().fold(f64::INFINITY, f64::min);
            assert!(
                lowest >= -1e-10 * kmax,
                "{name}: K has a negative eigenvalue {lowest}"
            );
            let second = {
                let mut e = eigen.clone();
                e.sort_by(|a, b| a.partial_cmp(b).unwrap());
                e[1]
            };
            assert!(
                second > 1e-9 * kmax,
                "{name}: second eigenvalue {second} (null space too large)"
            );
        }
    }
}

#[test]
fn random_quadratic_forms_are_non_negative() {
    let (_, mesh) = corpus().remove(2);
    let l = cotan_laplacian(&mesh.points, &mesh.triangles).unwrap();
    let ml = lumped_mass(&mesh.points, &mesh.triangles).unwrap();
    let k = biharmonic(&l, &ml).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..50 {
        let f: Vec<f64> = (0..mesh.points.len())
            .map(|_| rng.random_range(-1.0..1.0))
            .collect();
        let kf = apply(&k, &f);
        let q: f64 = f.iter().zip(&kf).map(|(a, b)| a * b).sum();
        assert!(q > 0.0, "fᵀKf = {q} for a random non-constant f");
    }
}

#[test]
fn degenerate_triangles_are_reported_with_their_index() {
    let points = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0]];
    let err = mass_matrix(&points, &[[0, 1, 3], [0, 1, 2]])
        .unwrap_err()
        .to_string();
    assert!(err.contains("triangle 1"), "{err}");
}

/// On a surface in 3-D (the face-anchored mesh's domain) the operators are intrinsic: a planar
/// mesh rotated out of its plane gives the same M, M_l and L as in 2-D.
#[test]
fn surface_operators_are_intrinsic() {
    for (name, mesh) in corpus() {
        let (a, b) = (0.7f64, -0.4f64);
        let lifted: Vec<[f64; 3]> = mesh
            .points
            .iter()
            .map(|p| {
                // Rotate (x, y, 0) about the x axis by a, then about the z axis by b, and shift.
                let (y, z) = (p[1] * a.cos(), p[1] * a.sin());
                let (x, y) = (p[0] * b.cos() - y * b.sin(), p[0] * b.sin() + y * b.cos());
                [x + 3.0, y - 1.0, z + 2.0]
            })
            .collect();
        let pairs = [
            (
                mass_matrix(&mesh.points, &mesh.triangles).unwrap(),
                mass_matrix(&lifted, &mesh.triangles).unwrap(),
            ),
            (
                cotan_laplacian(&mesh.points, &mesh.triangles).unwrap(),
                cotan_laplacian(&lifted, &mesh.triangles).unwrap(),
            ),
        ];
        for (flat, surface) in &pairs {
            let mut worst = 0.0f64;
            for_each_entry(flat, |i, j, v| {
                worst = worst.max((v - entry(surface, i, j)).abs() / v.abs().max(1.0));
            });
            assert!(worst < 1e-9, "{name}: {worst}");
        }
        let ml = lumped_mass(&mesh.points, &mesh.triangles).unwrap();
        let ml3 = lumped_mass(&lifted, &mesh.triangles).unwrap();
        for (p, q) in ml.iter().zip(&ml3) {
            assert!((p - q).abs() < 1e-9 * p);
        }
    }
}
