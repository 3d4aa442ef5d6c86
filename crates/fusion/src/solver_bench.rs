//! Set-up and per-frame cost of the factor-once solver at several mesh sizes (the reuse
//! regime of ERRATA 14): a regular grid over a smooth surface, meshed and factored as a depth
//! sequence would be, then the streaming step and the triangular solves timed, and the
//! factorisation repeated with each kernel and ordering.

use std::time::Instant;

use faer::Mat;
use serde::Serialize;
use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_fem::domain::domain_coordinates;
use visage_fem::{
    nested_dissection, FactorVariant, Factorization, FusionSystem, StreamingSolver, Weights,
};
use visage_mesh::{Mask, TriangulationKind};

use crate::{FusionError, FusionSetup, MeshingOptions};

/// One mesh size's measurements.
#[derive(Clone, Debug, Serialize)]
pub struct SizeReport {
    pub vertices: usize,
    pub image: [u32; 2],
    pub nnz_matrix: usize,
    pub factor_nnz: usize,
    /// Symbolic analysis + numeric factorisation of the streaming matrix.
    pub factor_ms: f64,
    /// Meshing and operator assembly.
    pub setup_ms: f64,
    /// One streaming step (3 right-hand-side columns, solve + residual check): median, p95.
    pub step_ms_median: f64,
    pub step_ms_p95: f64,
    /// The triangular solves alone, 3 columns in one call: median.
    pub solve3_ms_median: f64,
    /// Three single-column solves: median of their sum.
    pub solve1x3_ms_median: f64,
    /// The same factorisation forced to each kernel: factor time and 3-column solve median.
    pub variants: Vec<VariantReport>,
}

/// One factorisation kernel and ordering.
#[derive(Clone, Debug, Serialize)]
pub struct VariantReport {
    pub variant: FactorVariant,
    pub ordering: &'static str,
    pub factor_nnz: usize,
    pub factor_ms: f64,
    pub solve3_ms_median: f64,
}

/// What [`bench_solver`] measured.
#[derive(Clone, Debug, Serialize)]
pub struct SolverBench {
    pub threads: &'static str,
    pub weights: Weights,
    pub sizes: Vec<SizeReport>,
}

fn quantile(samples: &mut [f64], q: f64) -> f64 {
    samples.sort_by(f64::total_cmp);
    samples[((samples.len() - 1) as f64 * q).round() as usize]
}

fn time_ms(mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    f();
    start.elapsed().as_secs_f64() * 1e3
}

/// Measures the solver at about `sizes` vertices each, `repeats` timed solves per figure.
///
/// # Errors
/// Invalid weights, `repeats` = 0, a size under 16 vertices.
pub fn bench_solver(
    sizes: &[usize],
    repeats: usize,
    weights: Weights,
) -> Result<SolverBench, FusionError> {
    weights.validate()?;
    if repeats == 0 {
        return Err(FusionError::InvalidOption {
            name: "repeats",
            value: "0".into(),
            reason: "must be positive",
        });
    }
    let mut reports = Vec::new();
    for &n in sizes {
        if n < 16 {
            return Err(FusionError::InvalidOption {
                name: "size",
                value: n.to_string(),
                reason: "must be at least 16 vertices",
            });
        }
        // A 4:3 grid of n vertices at 4-pixel spacing over a smooth surface.
        let spacing = 4u32;
        let cols = ((n as f64 * 4.0 / 3.0).sqrt()).round().max(2.0) as u32;
        let rows = ((n as f64) / cols as f64).round().max(2.0) as u32;
        let (w, h) = (spacing * (cols - 1) + 1, spacing * (rows - 1) + 1);
        let k = Intrinsics::from_fov(w, h, 60.0)?;
        let mut depth = DepthMap::empty(w, h, DepthKind::Z);
        for v in 0..h {
            for u in 0..w {
                let (x, y) = (u as f64 / w as f64, v as f64 / h as f64);
                depth.data[(v * w + u) as usize] =
                    (0.6 + 0.05 * (6.0 * x).sin() * (5.0 * y).cos()) as f32;
            }
        }
        let setup_start = Instant::now();
        let options = MeshingOptions {
            spacing,
            triangulation: TriangulationKind::Planar,
            refine_tolerance_m: None,
        };
        let setup = FusionSetup::new(&k, &Mask::filled(w, h, true), &depth, &options)?;
        let setup_ms = setup_start.elapsed().as_secs_f64() * 1e3;
        let system = FusionSystem::new(setup.ops.clone(), weights)?;
        let a = system.matrix_temporal().clone();
        let start = Instant::now();
        let mut factor = Factorization::new(&a)?;
        let factor_ms = start.elapsed().as_secs_f64() * 1e3;
        let nv = setup.vertex_count();
        let mut solver = StreamingSolver::new(system);
        let mut b = Mat::<f64>::zeros(nv, 3);
        let fill = Mat::<f64>::zeros(nv, 3);
        setup
            .quadrature
            .assemble_rhs(&depth, f64::INFINITY, fill.as_ref(), b.as_mut());
        let mut x = Mat::<f64>::zeros(nv, 3);
        solver.step(b.as_ref(), x.as_mut()); // first frame: reset matrix; later: streaming
        let (mut step, mut solve3, mut solve1) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..repeats {
            step.push(time_ms(|| {
                solver.step(b.as_ref(), x.as_mut());
            }));
            let mut y = b.clone();
            solve3.push(time_ms(|| factor.solve_in_place(y.as_mut())));
            let mut y = b.clone();
            solve1.push(time_ms(|| {
                for c in 0..3 {
                    factor.solve_in_place(y.as_mut().subcols_mut(c, 1));
                }
            }));
        }
        let mut variants = Vec::new();
        let xi = domain_coordinates(&setup.mesh.points, &k);
        let mut nd = Vec::new();
        let nd_ms = time_ms(|| nd = nested_dissection(&xi, &a));
        let orders: [(&'static str, Option<&[usize]>); 2] =
            [("amd", None), ("nested-dissection", Some(&nd))];
        for (variant, (ordering, order)) in [FactorVariant::Simplicial, FactorVariant::Supernodal]
            .into_iter()
            .flat_map(|v| orders.iter().map(move |o| (v, *o)))
        {
            let start = Instant::now();
            let mut f = Factorization::with_options(&a, variant, order)?;
            let factor_ms =
                start.elapsed().as_secs_f64() * 1e3 + if order.is_some() { nd_ms } else { 0.0 };
            let mut times: Vec<f64> = (0..repeats)
                .map(|_| {
                    let mut y = b.clone();
                    time_ms(|| f.solve_in_place(y.as_mut()))
                })
                .collect();
            variants.push(VariantReport {
                variant,
                ordering,
                factor_nnz: f.factor_nnz(),
                factor_ms,
                solve3_ms_median: quantile(&mut times, 0.5),
            });
        }
        reports.push(SizeReport {
            vertices: nv,
            image: [w, h],
            nnz_matrix: a.compute_nnz(),
            factor_nnz: factor.factor_nnz(),
            factor_ms,
            setup_ms,
            step_ms_median: quantile(&mut step, 0.5),
            step_ms_p95: quantile(&mut step, 0.95),
            solve3_ms_median: quantile(&mut solve3, 0.5),
            solve1x3_ms_median: quantile(&mut solve1, 0.5),
            variants,
        });
    }
    Ok(SolverBench {
        threads: "single (faer Par::Seq)",
        weights,
        sizes: reports,
    })
}
