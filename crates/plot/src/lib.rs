//! Small hand-written SVG charts (no plotting dependency): the benchmark's and the run
//! report's line, x–y and heat-map charts.

#![forbid(unsafe_code)]

use std::fmt::Write as _;

/// One line of a chart: `values[i]` is plotted at x = `first_x + i`.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub name: String,
    pub values: Vec<f64>,
    pub first_x: f64,
}

const COLORS: [&str; 8] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
];
const W: f64 = 640.0;
const H: f64 = 400.0;
const PAD: f64 = 50.0;

/// An axis label: up to three decimals, trailing zeros dropped.
fn tick(v: f64) -> String {
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A line chart with axes, min/max labels and a legend. Non-finite values are skipped.
pub fn line_chart_svg(title: &str, x_label: &str, series: &[Series]) -> String {
    let curves: Vec<XySeries> = series
        .iter()
        .map(|se| XySeries {
            name: se.name.clone(),
            points: se
                .values
                .iter()
                .enumerate()
                .map(|(i, &v)| (se.first_x + i as f64, v))
                .collect(),
            markers: false,
        })
        .collect();
    xy_chart_svg(title, x_label, "", &curves)
}

/// One curve of an x–y chart: points joined in order (a non-finite point lifts the pen),
/// with a dot on each when `markers`.
#[derive(Clone, Debug, PartialEq)]
pub struct XySeries {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub markers: bool,
}

/// An x–y chart with axes, min/max labels and a legend; the y axis starts at 0 or below.
pub fn xy_chart_svg(title: &str, x_label: &str, y_label: &str, series: &[XySeries]) -> String {
    let finite = series.iter().flat_map(|s| {
        s.points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
    });
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, 0.0f64, f64::MIN);
    for (x, y) in finite {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 > x1 {
        (x0, x1, y1) = (0.0, 1.0, 1.0);
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if y1 <= y0 {
        y1 = y0 + 1.0;
    }
    let px = |x: f64| PAD + (x - x0) / (x1 - x0) * (W - 2.0 * PAD);
    let py = |y: f64| H - PAD - (y - y0) / (y1 - y0) * (H - 2.0 * PAD);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{W}" height="{H}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="20" text-anchor="middle" font-size="14">{}</text>"#,
        W / 2.0,
        escape(title)
    );
    let _ = writeln!(
        s,
        r#"<path d="M{PAD} {} L{} {} M{PAD} {} L{PAD} {PAD}" stroke="black" fill="none"/>"#,
        H - PAD,
        W - PAD,
        H - PAD,
        H - PAD
    );
    let _ = writeln!(
        s,
        r#"<text x="{PAD}" y="{}" text-anchor="middle">{}</text>"#,
        H - PAD + 15.0,
        tick(x0)
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
        W - PAD,
        H - PAD + 15.0,
        tick(x1)
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
        W / 2.0,
        H - 12.0,
        escape(x_label)
    );
    if !y_label.is_empty() {
        let _ = writeln!(
            s,
            r#"<text x="14" y="{}" text-anchor="middle" transform="rotate(-90 14 {})">{}</text>"#,
            H / 2.0,
            H / 2.0,
            escape(y_label)
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="end">{y0:.3}</text>"#,
        PAD - 4.0,
        H - PAD
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="end">{y1:.3}</text>"#,
        PAD - 4.0,
        PAD + 4.0
    );
    for (k, se) in series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let mut d = String::new();
        let mut pen_down = false;
        for &(x, y) in &se.points {
            if !(x.is_finite() && y.is_finite()) {
                pen_down = false;
                continue;
            }
            let _ = write!(
                d,
                "{}{:.1} {:.1} ",
                if pen_down { "L" } else { "M" },
                px(x),
                py(y)
            );
            pen_down = true;
            if se.markers {
                let _ = writeln!(
                    s,
                    r#"<circle cx="{:.1}" cy="{:.1}" r="3" fill="{color}"/>"#,
                    px(x),
                    py(y)
                );
            }
        }
        let _ = writeln!(
            s,
            r#"<path d="{}" stroke="{color}" stroke-width="1.5" fill="none"/>"#,
            d.trim_end()
        );
        let ly = PAD + 16.0 * k as f64;
        let _ = writeln!(
            s,
            r#"<line x1="{}" y1="{ly}" x2="{}" y2="{ly}" stroke="{color}" stroke-width="2"/>"#,
            W - PAD - 150.0,
            W - PAD - 130.0
        );
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}">{}</text>"#,
            W - PAD - 125.0,
            ly + 4.0,
            escape(&se.name)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// A heat map of `values` (row-major, rows = `rows`, columns = `cols`), darker = smaller, with
/// each cell's value written in it.
///
/// # Panics
/// If `values.len() != rows.len() * cols.len()`.
#[track_caller]
pub fn heatmap_svg(title: &str, rows: &[f64], cols: &[f64], values: &[f64]) -> String {
    assert!(values.len() == rows.len() * cols.len());
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let lo = finite.iter().copied().fold(f64::MAX, f64::min);
    let hi = finite.iter().copied().fold(f64::MIN, f64::max);
    let (cw, ch) = (70.0, 30.0);
    let (w, h) = (
        PAD + 20.0 + cw * cols.len() as f64,
        PAD + 20.0 + ch * rows.len() as f64,
    );
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="4" y="14" font-size="12">{}</text>"#,
        escape(title)
    );
    for (j, c) in cols.iter().enumerate() {
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" text-anchor="middle">μ={c}</text>"#,
            PAD + 20.0 + cw * (j as f64 + 0.5),
            PAD - 4.0
        );
    }
    for (i, r) in rows.iter().enumerate() {
        let y = PAD + ch * i as f64;
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" text-anchor="end">λ={r}</text>"#,
            PAD + 16.0,
            y + ch / 2.0 + 4.0
        );
        for j in 0..cols.len() {
            let v = values[i * cols.len() + j];
            let t = if hi > lo && v.is_finite() {
                (v - lo) / (hi - lo)
            } else {
                0.5
            };
            let g = (60.0 + 195.0 * t) as u8;
            let x = PAD + 20.0 + cw * j as f64;
            let _ = writeln!(
                s,
                r#"<rect x="{x}" y="{y}" width="{cw}" height="{ch}" fill="rgb({g},{g},255)"/>"#
            );
            let _ = writeln!(
                s,
                r#"<text x="{}" y="{}" text-anchor="middle">{v:.3}</text>"#,
                x + cw / 2.0,
                y + ch / 2.0 + 4.0
            );
        }
    }
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn charts_are_well_formed_and_escape_text() {
        let s = line_chart_svg(
            "a < b",
            "frame",
            &[Series {
                name: "raw".into(),
                values: vec![1.0, f64::NAN, 2.0, 3.0],
                first_x: 0.0,
            }],
        );
        assert!(s.starts_with("<svg") && s.trim_end().ends_with("</svg>"));
        assert!(s.contains("a &lt; b") && s.contains("M50.0") && s.contains(">raw<"));
        let h = heatmap_svg("t", &[1.0, 2.0], &[3.0], &[0.5, 0.7]);
        assert_eq!(h.matches("<rect x=").count(), 2);
    }
}
