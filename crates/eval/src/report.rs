//! Outputs of a benchmark run: `results.json`, `results.csv`, SVG plots and a text table.

use std::fmt::Write as _;
use std::path::Path;

use crate::benchmark::{BenchmarkResults, SweepPoint};
use crate::EvalError;
use visage_plot::{heatmap_svg, line_chart_svg, Series};

/// Table order of the methods (then any others, by name).
const ORDER: [&str; 6] = [
    "raw",
    "per_frame_biharmonic",
    "taubin",
    "streaming",
    "streaming_sift_anchors",
    "clip",
];

fn ordered(results: &BenchmarkResults) -> Vec<&str> {
    let mut names: Vec<&str> = ORDER
        .iter()
        .copied()
        .filter(|n| results.methods.contains_key(*n))
        .collect();
    names.extend(
        results
            .methods
            .keys()
            .map(String::as_str)
            .filter(|n| !ORDER.contains(n)),
    );
    names
}

fn write(path: &Path, text: &str) -> Result<(), EvalError> {
    std::fs::write(path, text).map_err(|source| EvalError::Io {
        path: path.to_owned(),
        source,
    })
}

/// The table printed on stdout (one row per method).
pub fn table(results: &BenchmarkResults) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<22} {:>9} {:>10} {:>10} {:>11} {:>6} {:>10} {:>10} {:>9}",
        "method",
        "rmse_mm",
        "median_mm",
        "rmse@scale",
        "jitter_mm",
        "lag",
        "curv_impr",
        "rough_deg",
        "ms/frame"
    );
    for name in ordered(results) {
        let m = &results.methods[name];
        let _ = writeln!(
            s,
            "{:<22} {:>9.3} {:>10.3} {:>10.3} {:>11.3} {:>6.2} {:>10.2} {:>10.2} {:>9.2}",
            name,
            m.rmse_mm,
            m.median_mm,
            m.rmse_scaled_mm,
            m.jitter_mm,
            m.lag_frames,
            m.curvature_improvement,
            m.roughness.to_degrees(),
            m.ms_per_frame
        );
    }
    if let Some(f) = &results.model_fit {
        let m = &f.mean;
        let _ = writeln!(
            s,
            "face model fit ({} sequences): expression MAE {:.3} (all-zero guess {:.3}), identity \
             {:.2} mm after scale (scale off by {:.1} %), reprojection {:.2} px, {:.2} ms/frame",
            f.sequences,
            m.expression_mae,
            m.zero_guess_mae,
            m.identity_rmse_mm,
            100.0 * m.identity_scale_error,
            m.reprojection_px,
            m.ms_per_frame
        );
    }
    if let Some(a) = &results.alignment {
        let _ = writeln!(
            s,
            "relative depth aligned to the fitted face: {} frames ({} failed), residual median \
             {:.2} mm, 95th percentile {:.2} mm",
            a.frames, a.failed, a.median_residual_mm, a.p95_residual_mm
        );
    }
    s
}

/// The CSV form of the method table (roughness in radians, as in `results.json`).
pub fn csv(results: &BenchmarkResults) -> String {
    let mut s = String::from(
        "method,rmse_mm,median_mm,rmse_scaled_mm,scale_error,jitter_mm,lag_frames,curvature_improvement,roughness,mean_abs_h,ms_per_frame,samples\n",
    );
    for name in ordered(results) {
        let m = &results.methods[name];
        let _ = writeln!(
            s,
            "{name},{},{},{},{},{},{},{},{},{},{},{}",
            m.rmse_mm,
            m.median_mm,
            m.rmse_scaled_mm,
            m.scale_error,
            m.jitter_mm,
            m.lag_frames,
            m.curvature_improvement,
            m.roughness,
            m.mean_abs_h,
            m.ms_per_frame,
            m.samples
        );
    }
    s
}

/// The sweep as a fixed-width text table, one line per (λ, μ).
pub fn sweep_table(points: &[SweepPoint]) -> String {
    let mut s = format!(
        "{:>8} {:>8} {:>9} {:>10} {:>10} {:>6}\n",
        "lambda", "mu", "rmse_mm", "rmse@scale", "jitter_mm", "lag"
    );
    for p in points {
        let _ = writeln!(
            s,
            "{:>8} {:>8} {:>9.3} {:>10.3} {:>10.3} {:>6.2}",
            p.lambda, p.mu, p.rmse_mm, p.rmse_scaled_mm, p.jitter_mm, p.lag_frames
        );
    }
    s
}

/// Writes `results.json`, `results.csv`, `error_per_frame.svg` and `jitter_per_frame.svg` into
/// `out` (which must exist).
pub fn write_results(results: &BenchmarkResults, out: &Path) -> Result<(), EvalError> {
    let json = serde_json::to_string_pretty(results).map_err(|e| EvalError::Io {
        path: out.join("results.json"),
        source: e.into(),
    })?;
    write(&out.join("results.json"), &json)?;
    write(&out.join("results.csv"), &csv(results))?;
    let names = ordered(results);
    for (file, title, pick) in [
        ("error_per_frame.svg", "RMS surface error (mm)", 0),
        ("jitter_per_frame.svg", "Jitter (mm/frame)", 1),
    ] {
        let series: Vec<Series> = names
            .iter()
            .map(|n| {
                let p = &results.per_frame[*n];
                let v = if pick == 0 { &p.rmse_mm } else { &p.jitter_mm };
                Series {
                    name: n.to_string(),
                    values: v.iter().copied().skip(pick).collect(),
                    first_x: pick as f64,
                }
            })
            .collect();
        write(&out.join(file), &line_chart_svg(title, "frame", &series))?;
    }
    Ok(())
}

/// Writes `sweep.json`, `sweep.csv` and the heat maps `sweep_rmse.svg`, `sweep_jitter.svg`.
pub fn write_sweep(
    points: &[SweepPoint],
    lambdas: &[f64],
    mus: &[f64],
    out: &Path,
) -> Result<(), EvalError> {
    let json = serde_json::to_string_pretty(points).map_err(|e| EvalError::Io {
        path: out.join("sweep.json"),
        source: e.into(),
    })?;
    write(&out.join("sweep.json"), &json)?;
    let mut csv = String::from("lambda,mu,rmse_mm,rmse_scaled_mm,jitter_mm,lag_frames\n");
    for p in points {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{}",
            p.lambda, p.mu, p.rmse_mm, p.rmse_scaled_mm, p.jitter_mm, p.lag_frames
        );
    }
    write(&out.join("sweep.csv"), &csv)?;
    for (file, title, f) in [
        (
            "sweep_rmse.svg",
            "streaming RMSE (mm) over λ (rows) × μ (columns)",
            0,
        ),
        (
            "sweep_jitter.svg",
            "streaming jitter (mm/frame) over λ (rows) × μ (columns)",
            1,
        ),
    ] {
        let values: Vec<f64> = points
            .iter()
            .map(|p| if f == 0 { p.rmse_mm } else { p.jitter_mm })
            .collect();
        write(&out.join(file), &heatmap_svg(title, lambdas, mus, &values))?;
    }
    Ok(())
}
