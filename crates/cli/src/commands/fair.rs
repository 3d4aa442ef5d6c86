//! `visage fair`: Willmore-type fairing of one mesh with soft positional constraints (paper §5,
//! Eq. (5.3) as corrected), solved by preconditioned conjugate gradients.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
use clap::Args;
use visage_fem::{
    boundary_vertices, fair, FairingConstraints, FairingOptions, Preconditioner, SurfaceMetrics,
};

/// Arguments of `visage fair`.
#[derive(Args, Debug)]
pub struct FairArgs {
    /// The mesh (.obj or .ply; metres).
    pub mesh: PathBuf,
    /// The faired mesh (.ply or .obj).
    #[arg(long)]
    pub out: PathBuf,
    /// Smoothing length in millimetres: bumps much smaller are flattened, shapes much larger
    /// kept (γ = ℓ⁻⁴).
    #[arg(long, default_value_t = 2.0, conflicts_with = "gamma")]
    pub length_mm: f64,
    /// The positional weight γ directly, 1/m⁴.
    #[arg(long)]
    pub gamma: Option<f64>,
    /// Constraints JSON: {"constraints": [{"vertex": i, "position": [x, y, z], "weight": w}]}
    /// (weight in [0, 1]); listed vertices are pulled to their position with their weight,
    /// the others to where they are with `--data-weight`.
    #[arg(long)]
    pub constraints: Option<PathBuf>,
    /// Weight of the unlisted vertices' own positions (0: only the constraints hold the
    /// surface).
    #[arg(long, default_value_t = 1.0)]
    pub data_weight: f64,
    /// Outer iterations (operators re-measured on the result).
    #[arg(long, default_value_t = FairingOptions::default().outer_iterations)]
    pub iterations: usize,
    /// Precondition with the diagonal instead of the Cholesky factorisation.
    #[arg(long)]
    pub jacobi: bool,
}

/// Runs `visage fair`; prints a JSON report (iterations, residual, roughness and mean |H|
/// before and after, time).
pub fn run(args: FairArgs) -> anyhow::Result<()> {
    let mut mesh = visage_mesh::io::read_mesh(&args.mesh)?;
    let n = mesh.vertices.len();
    if n == 0 || mesh.triangles.is_empty() {
        bail!(
            "{}: the mesh is empty: nothing to fair",
            args.mesh.display()
        );
    }
    if !(args.length_mm.is_finite() && args.length_mm > 0.0) {
        bail!("--length-mm {} must be positive", args.length_mm);
    }
    let gamma = args.gamma.unwrap_or((args.length_mm * 1e-3).powi(-4));
    if !(gamma.is_finite() && gamma > 0.0) {
        bail!("--gamma {gamma} must be positive and finite");
    }
    if !(0.0..=1.0).contains(&args.data_weight) {
        bail!("--data-weight {} must lie in [0, 1]", args.data_weight);
    }
    let mut targets = mesh.vertices.clone();
    let mut weights = vec![args.data_weight; n];
    if let Some(path) = &args.constraints {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read the constraints", path.display()))?;
        FairingConstraints::parse_json(&text, path, n)?.apply(&mut targets, &mut weights);
    }
    let options = FairingOptions {
        gamma,
        outer_iterations: args.iterations.max(1),
        preconditioner: if args.jacobi {
            Preconditioner::Jacobi
        } else {
            Preconditioner::Cholesky
        },
        max_iterations: if args.jacobi { 20_000 } else { 200 },
        ..FairingOptions::default()
    };
    let start = Instant::now();
    let (faired, report) = fair(
        &mesh.vertices,
        &mesh.triangles,
        &targets,
        &weights,
        &options,
    )
    .with_context(|| format!("{}: cannot fair the mesh", args.mesh.display()))?;
    let ms = start.elapsed().as_secs_f64() * 1e3;
    let mut metrics =
        SurfaceMetrics::new(n, &mesh.triangles, &boundary_vertices(n, &mesh.triangles));
    let before = metrics.evaluate(&mesh.vertices);
    let after = metrics.evaluate(&faired);
    mesh.vertices = faired;
    mesh.normals.clear();
    visage_mesh::io::write_mesh(&args.out, &mesh)?;
    let json = serde_json::json!({
        "gamma_per_m4": gamma,
        "iterations": report.iterations,
        "relative_residual": report.relative_residual,
        "ms": ms,
        "mean_abs_h": {"input": before.mean_abs_h, "faired": after.mean_abs_h},
        "roughness": {"input": before.roughness, "faired": after.roughness},
    });
    println!("{}", serde_json::to_string_pretty(&json)?);
    Ok(())
}
