//! Line and x–y charts drawn with `plotters`: ticks on both axes, a grid, the axes' labels and
//! the legend in a column right of the data, the y range from the data.

use plotters::prelude::*;

/// One line of a chart: `values[i]` is plotted at x = `first_x + i`.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub name: String,
    pub values: Vec<f64>,
    pub first_x: f64,
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

/// The y range drawn for data from `lo` to `hi`: the data's own range with a margin, from 0
/// when the data start near it (weights, errors), so a curve far from 0 is not a flat line
/// at the top.
fn y_range(lo: f64, hi: f64) -> (f64, f64) {
    let span = (hi - lo).max(hi.abs() * 1e-3).max(1e-9);
    let lo = if lo >= 0.0 && lo < 0.25 * hi {
        0.0
    } else {
        lo - 0.05 * span
    };
    (lo, hi + 0.05 * span)
}

/// An x–y chart (plotters' SVG backend): a grid with ticks on both axes, the axes' labels and
/// the legend in a column right of the data, so no name is cut; the SVG scales to its
/// container (a `viewBox`, no fixed size).
pub fn xy_chart_svg(title: &str, x_label: &str, y_label: &str, series: &[XySeries]) -> String {
    let finite = series.iter().flat_map(|s| {
        s.points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
    });
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in finite {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    let (y0, y1) = y_range(y0, y1);
    let legend_width = series
        .iter()
        .map(|s| s.name.chars().count())
        .max()
        .map_or(0, |n| 44 + 9 * n as u32);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (W + legend_width, H)).into_drawing_area();
        // Drawing into a string cannot fail; a chart that could not be laid out is left empty.
        let _ = draw_xy(&root, title, x_label, y_label, series, (x0, x1), (y0, y1));
        let _ = draw_legend(&root, series, W);
        let _ = root.present();
    }
    responsive(svg)
}

const W: u32 = 640;
const H: u32 = 400;
const COLORS: [RGBColor; 8] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0x8c, 0x56, 0x4b),
    RGBColor(0xe3, 0x77, 0xc2),
    RGBColor(0x7f, 0x7f, 0x7f),
];

type Area<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;
type DrawResult<'a> =
    Result<(), DrawingAreaErrorKind<<SVGBackend<'a> as DrawingBackend>::ErrorType>>;

fn draw_xy<'a>(
    root: &Area<'a>,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[XySeries],
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> DrawResult<'a> {
    root.fill(&WHITE)?;
    let (area, _) = root.split_horizontally(W);
    let mut chart = ChartBuilder::on(&area)
        .caption(title, ("sans-serif", 19))
        .margin(10)
        .x_label_area_size(48)
        .y_label_area_size(if y_label.is_empty() { 56 } else { 76 })
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_labels(8)
        .y_labels(6)
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 15))
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(205, 205, 205))
        .draw()?;
    for (k, se) in series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        // A non-finite point lifts the pen: each finite run is its own line.
        for run in se
            .points
            .split(|(x, y)| !(x.is_finite() && y.is_finite()))
            .filter(|r| !r.is_empty())
        {
            chart.draw_series(LineSeries::new(run.iter().copied(), color.stroke_width(2)))?;
            if se.markers {
                chart.draw_series(run.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
            }
        }
    }
    Ok(())
}

/// The legend in its own column right of the chart: a colour swatch and the whole name.
fn draw_legend<'a>(root: &Area<'a>, series: &[XySeries], left: u32) -> DrawResult<'a> {
    let font = ("sans-serif", 15).into_font().color(&BLACK);
    for (k, se) in series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let y = 44 + 22 * k as i32;
        let x = left as i32 + 8;
        root.draw(&PathElement::new(
            vec![(x, y), (x + 22, y)],
            color.stroke_width(3),
        ))?;
        root.draw(&Text::new(se.name.clone(), (x + 28, y - 9), font.clone()))?;
    }
    Ok(())
}

/// plotters writes a fixed `width` and `height`; a `viewBox` and a width of 100 % let the page
/// size the chart to its container with its proportions kept.
fn responsive(svg: String) -> String {
    let Some(start) = svg.find("<svg") else {
        return svg;
    };
    let end = start + svg[start..].find('>').unwrap_or(0);
    let tag = &svg[start..end];
    let attr = |name: &str| -> Option<String> {
        let i = tag.find(&format!(" {name}=\""))? + name.len() + 3;
        let j = i + tag[i..].find('"')?;
        Some(tag[i..j].to_string())
    };
    let (Some(w), Some(h)) = (attr("width"), attr("height")) else {
        return svg;
    };
    let new_tag = tag
        .replacen(&format!(" width=\"{w}\""), " width=\"100%\"", 1)
        .replacen(&format!(" height=\"{h}\""), "", 1);
    let new_tag = if new_tag.contains("viewBox") {
        new_tag
    } else {
        format!("{new_tag} viewBox=\"0 0 {w} {h}\"")
    };
    format!("{}{}{}", &svg[..start], new_tag, &svg[end..])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn charts_are_well_formed_scale_to_their_container_and_escape_text() {
        let s = line_chart_svg(
            "a < b",
            "frame",
            &[Series {
                name: "a long name that a legend inside the data would cut".into(),
                values: vec![1.0, 1.5, f64::NAN, 2.0, 3.0],
                first_x: 0.0,
            }],
        );
        assert!(s.starts_with("<svg") && s.trim_end().ends_with("</svg>"));
        let tag = &s[..s.find('>').unwrap()];
        assert!(
            tag.contains("viewBox=\"0 0 ") && tag.contains("width=\"100%\""),
            "{tag}"
        );
        assert!(!tag.contains("height="), "{tag}");
        assert!(s.contains("a &lt; b"), "the title is escaped");
        assert!(s.contains("a long name that a legend inside the data would cut"));
        // The NaN lifts the pen: two lines in the first colour, and the legend's swatch.
        let first_colour = s
            .lines()
            .filter(|l| l.starts_with("<polyline") && l.contains("stroke=\"#1F77B4\""));
        assert_eq!(first_colour.count(), 3, "{s}");
    }

    #[test]
    fn the_y_range_starts_at_zero_only_for_data_near_it() {
        assert_eq!(y_range(0.02, 1.0).0, 0.0);
        let (lo, hi) = y_range(0.9, 1.0);
        assert!(lo > 0.8 && lo < 0.9 && hi > 1.0, "{lo} {hi}");
        let (lo, _) = y_range(-1.0, 1.0);
        assert!(lo < -1.0);
    }
}
