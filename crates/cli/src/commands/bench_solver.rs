//! `visage bench-solver`: set-up and per-frame cost of the factor-once solver at several mesh
//! sizes, printed as JSON (paper §4; the reuse regime of ERRATA 14).

use std::time::Instant;

use anyhow::Context;
use clap::Args;
use faer::Mat;
use serde::Serialize;
use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_fem::domain::domain_coordinates;
use visage_fem::{
    nested_dissection, FactorVariant, Factorization, FusionSystem, StreamingSolver, Weights,
};
use visage_mesh::{Mask, TriangulationKind};
use visage_pipeline::{FusionSetup, MeshingOptions};

/// Arguments of `visage bench-solver`.
#[derive(Args, Debug)]
pub struct BenchSolverArgs {
    /// Approximate vertex counts to measure.
    #[arg(long, value_delimiter = ',', default_value = "10000,20000,40000")]
    sizes: Vec<usize>,
    /// Timed repetitions of the per-frame solve.
    #[arg(long, default_value_t = 50)]
    repeats: usize,
    /// Smoothness weight λ.
    #[arg(long, default_value_t = Weights::default().lambda)]
    lambda: f64,
    /// Temporal weight μ.
    #[arg(long, default_value_t = Weights::default().mu)]
    mu: f64,
}

#[derive(Serialize)]
struct SizeReport {
    vertices: usize,
    image: [u32; 2],
    nnz_matrix: usize,
    factor_nnz: usize,
    /// Symbolic analysis + numeric factorisation of the streaming matrix.
    factor_ms: f64,
    /// Meshing and operator assembly.
    setup_ms: f64,
    /// One streaming step (3 right-hand-side columns, solve + residual check): median, p95.
    step_ms_median: f64,
    step_ms_p95: f64,
    /// The triangular solves alone, 3 columns in one call: median.
    solve3_ms_median: f64,
    /// Three single-column solves: median of their sum.
    solve1x3_ms_median: f64,
    /// The same factorisation forced to each kernel: factor time and 3-column solve median.
    variants: Vec<VariantReport>,
}

#[derive(Serialize)]
struct VariantReport {
    variant: FactorVariant,
    ordering: &'static str,
    factor_nnz: usize,
    factor_ms: f64,
    solve3_ms_median: f64,
}

#[derive(Serialize)]
struct BenchReport {
    threads: &'static str,
    weights: Weights,
    sizes: Vec<SizeReport>,
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

pub fn run(args: BenchSolverArgs) -> anyhow::Result<()> {
    let weights = Weights {
        lambda: args.lambda,
        mu: args.mu,
    };
    weights.validate()?;
    anyhow::ensure!(args.repeats > 0, "--repeats must be positive");
    let mut sizes = Vec::new();
    for &n in &args.sizes {
        anyhow::ensure!(n >= 16, "size {n} is too small");
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
        let setup =
            FusionSetup::new(&k, &Mask::filled(w, h, true), &depth, &options).context("meshing")?;
        let setup_ms = setup_start.elapsed().as_secs_f64() * 1e3;
        let system = FusionSystem::new(setup.ops.clone(), weights)?;
        let a = system.matrix_temporal().clone();
        let mut factor = None;
        let factor_ms = time_ms(|| factor = Some(Factorization::new(&a)));
        let mut factor = factor.context("unreachable")??;
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
        for _ in 0..args.repeats {
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
            let mut f = None;
            let factor_ms = time_ms(|| f = Some(Factorization::with_options(&a, variant, order)))
                + if order.is_some() { nd_ms } else { 0.0 };
            let mut f = f.context("unreachable")??;
            let mut times: Vec<f64> = (0..args.repeats)
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
        sizes.push(SizeReport {
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
    let report = BenchReport {
        threads: "single (faer Par::Seq)",
        weights,
        sizes,
    };
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}
