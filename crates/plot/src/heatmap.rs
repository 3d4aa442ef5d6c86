//! A heat map as hand-written SVG: a table of coloured cells with their values, which a chart
//! library does not make simpler.

use std::fmt::Write as _;

/// The heat map's margin (px).
const PAD: f64 = 50.0;

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
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
    fn a_heat_map_has_a_cell_per_value() {
        let h = heatmap_svg("t", &[1.0, 2.0], &[3.0], &[0.5, 0.7]);
        assert_eq!(h.matches("<rect x=").count(), 2);
    }
}
