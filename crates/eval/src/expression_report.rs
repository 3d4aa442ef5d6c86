//! The expression benchmark's outputs: `results.json`, one SVG per take and shape with the
//! played and read curves over time (`plots/TAKE/SHAPE.svg`), and the printed table.

use std::fmt::Write as _;
use std::path::Path;

use visage_plot::{xy_chart_svg, XySeries};
use visage_rig::ARKIT_BLENDSHAPES;

use crate::expression_benchmark::{Curves, ExpressionResults, ExpressionSummary};
use crate::EvalError;

/// The shapes the table lists one by one.
pub const TABLE_SHAPES: [&str; 9] = [
    "jawOpen",
    "eyeBlinkLeft",
    "eyeBlinkRight",
    "mouthSmileLeft",
    "mouthSmileRight",
    "browInnerUp",
    "mouthFunnel",
    "mouthPucker",
    "eyeLookOutLeft",
];

/// Writes `out/results.json`, `out/plots/TAKE/SHAPE.svg` (played and read against time) and
/// `out/curves/TAKE.csv` (per frame with a face: time, the head's played and read yaw, pitch
/// and roll in degrees, then each shape's played and read weight).
///
/// # Errors
/// A folder or file that cannot be written.
pub fn write_expression_results(out: &Path, results: &ExpressionResults) -> Result<(), EvalError> {
    let json = serde_json::to_string_pretty(results).map_err(|e| EvalError::Io {
        path: out.join("results.json"),
        source: std::io::Error::other(e),
    })?;
    write(&out.join("results.json"), &json)?;
    for take in &results.takes {
        let dir = out.join("plots").join(&take.take);
        std::fs::create_dir_all(&dir).map_err(|source| EvalError::CreateDir {
            path: dir.clone(),
            source,
        })?;
        let c = &take.curves;
        let curves_dir = out.join("curves");
        std::fs::create_dir_all(&curves_dir).map_err(|source| EvalError::CreateDir {
            path: curves_dir.clone(),
            source,
        })?;
        write(
            &curves_dir.join(format!("{}.csv", take.take)),
            &curves_csv(c),
        )?;
        for (w, name) in ARKIT_BLENDSHAPES.iter().enumerate() {
            let series = |label: &str, values: &[[f32; 52]]| XySeries {
                name: label.to_string(),
                points: c
                    .time_s
                    .iter()
                    .zip(values)
                    .map(|(&t, v)| (t, f64::from(v[w])))
                    .collect(),
                markers: false,
            };
            let score = &take.shapes[*name];
            let title = format!(
                "{} — {name}: MAE {} (from rest {}), r {}",
                take.take,
                fmt(score.mae, 3),
                fmt(score.mae_from_rest, 3),
                fmt(score.r, 2)
            );
            let svg = xy_chart_svg(
                &title,
                "time (s)",
                "weight",
                &[
                    series("played", &c.played),
                    series("played from rest", &c.played_from_rest),
                    series("read", &c.read),
                ],
            );
            write(&dir.join(format!("{name}.svg")), &svg)?;
        }
    }
    Ok(())
}

/// One row per frame: `time_s`, `played_yaw … read_roll` (degrees), `played_SHAPE, read_SHAPE`
/// for each of the 52 shapes.
fn curves_csv(c: &Curves) -> String {
    let mut out =
        String::from("time_s,played_yaw,played_pitch,played_roll,read_yaw,read_pitch,read_roll");
    for name in ARKIT_BLENDSHAPES {
        let _ = write!(out, ",played_{name},read_{name}");
    }
    out.push('\n');
    for i in 0..c.time_s.len() {
        let _ = write!(out, "{:.4}", c.time_s[i]);
        for head in [&c.played_head, &c.read_head] {
            for a in head.get(i).copied().unwrap_or([f64::NAN; 3]) {
                let _ = write!(out, ",{:.3}", a.to_degrees());
            }
        }
        for w in 0..ARKIT_BLENDSHAPES.len() {
            let _ = write!(out, ",{:.4},{:.4}", c.played[i][w], c.read[i][w]);
        }
        out.push('\n');
    }
    out
}

fn write(path: &Path, text: &str) -> Result<(), EvalError> {
    std::fs::write(path, text).map_err(|source| EvalError::Io {
        path: path.to_owned(),
        source,
    })
}

fn fmt(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(|| "—".to_string(), |v| format!("{v:.digits$}"))
}

/// The summary of each take and of all, then MAE / r of [`TABLE_SHAPES`] per take.
pub fn expression_table(results: &ExpressionResults) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<28} {:>6} {:>6} {:>7} {:>8} {:>6} {:>7} {:>8} {:>7} {:>6} {:>8}",
        "take",
        "frames",
        "faces",
        "MAE",
        "MAE rest",
        "blink",
        "false",
        "leak p99",
        "rot°",
        "id mm",
        "ms/frame"
    );
    let row = |s: &mut String, name: &str, m: &ExpressionSummary| {
        let _ = writeln!(
            s,
            "{:<28} {:>6} {:>6} {:>7} {:>8} {:>6} {:>7} {:>8} {:>7} {:>6} {:>8.1}",
            name,
            m.frames,
            m.frames_with_face,
            fmt(m.mae, 4),
            fmt(m.mae_from_rest, 4),
            fmt(m.blink_hit_rate, 2),
            fmt(m.false_closure_rate, 4),
            fmt(m.rigid_leak_p99, 3),
            fmt(m.head_rotation_rmse_deg, 2),
            fmt(m.identity_error_mm, 2),
            m.ms_per_frame
        );
    };
    for t in &results.takes {
        row(&mut s, &t.take, &t.summary);
    }
    row(&mut s, "all", &results.summary);
    let _ = writeln!(
        s,
        "(MAE rest: against the played weights relative to the take's resting values)"
    );
    if let Some(floor) = results.summary.mae_floor {
        let _ = writeln!(
            s,
            "(a perfect reading relative to the rest would score MAE {floor:.4}: the takes' resting values)"
        );
    }
    if let Some((name, v)) = &results.summary.rigid_leak_worst {
        let _ = writeln!(s, "largest leak: {name} (p99 {v:.3})");
    }
    if let Some([y, p, r]) = results.summary.head_angle_rmse_deg {
        let _ = writeln!(
            s,
            "head angle RMSE: yaw {y:.2}°, pitch {p:.2}°, roll {r:.2}°"
        );
    }
    let _ = writeln!(s);
    let _ = write!(s, "{:<18}", "MAE / r / leak");
    for t in &results.takes {
        let _ = write!(s, " {:>20}", truncate(&t.take, 20));
    }
    let _ = writeln!(s, " {:>20}", "all");
    for name in TABLE_SHAPES {
        let _ = write!(s, "{name:<18}");
        for shapes in results
            .takes
            .iter()
            .map(|t| &t.shapes)
            .chain([&results.shapes])
        {
            let sc = &shapes[name];
            let cell = format!(
                "{} / {} / {}",
                fmt(sc.mae, 3),
                fmt(sc.r, 2),
                fmt(sc.leak_p99, 2)
            );
            let _ = write!(s, " {cell:>20}");
        }
        let _ = writeln!(s);
    }
    s
}

fn truncate(s: &str, n: usize) -> &str {
    match s.char_indices().nth(n) {
        Some((i, _)) => &s[..i],
        None => s,
    }
}
