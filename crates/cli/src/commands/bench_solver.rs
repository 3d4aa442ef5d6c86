//! `visage bench-solver`: set-up and per-frame cost of the factor-once solver at several mesh
//! sizes, printed as JSON.

use clap::Args;
use visage_fem::Weights;
use visage_fusion::bench_solver;

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

pub fn run(args: BenchSolverArgs) -> anyhow::Result<()> {
    let weights = Weights {
        lambda: args.lambda,
        mu: args.mu,
    };
    let report = bench_solver(&args.sizes, args.repeats, weights)?;
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}
