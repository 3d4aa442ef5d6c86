//! Line and x–y charts drawn with `plotters`: ticks on both axes, a grid, the axes' labels and
//! the legend in a column right of the data, the y range from the data; as SVG that scales to
//! its container, or as a PNG.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::font::{register_built_in_font, FAMILY};

/// One line of a chart: `values[i]` is plotted at x = `first_x + i`.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub name: String,
    pub values: Vec<f64>,
    pub first_x: f64,
}

/// One curve of an x–y chart: points joined in order (a non-finite point lifts the pen),
/// with a dot on each when `markers`.
#[derive(Clone, Debug, PartialEq)]
pub struct XySeries {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub markers: bool,
}

/// The data area's width and the chart's height at scale 1 (px); the legend's column adds to
/// the width.
const W: u32 = 640;
const H: u32 = 400;
/// How many times larger than the SVG's a PNG is drawn: 1280 × 800 pixels and the legend, its
/// text as large on a slide as the SVG's on a page.
const PNG_SCALE: u32 = 2;
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

/// An x–y chart (plotters' SVG backend): a grid with ticks on both axes, the axes' labels and
/// the legend in a column right of the data, so no name is cut; the SVG scales to its
/// container (a `viewBox`, no fixed size).
pub fn xy_chart_svg(title: &str, x_label: &str, y_label: &str, series: &[XySeries]) -> String {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, chart_size(series, 1)).into_drawing_area();
        draw_chart(&root, 1, title, x_label, y_label, series);
        let _ = root.present();
    }
    responsive(svg)
}

/// The chart of [`xy_chart_svg`] as a PNG (plotters' bitmap backend): the same layout drawn
/// twice as large, 1280 × 800 pixels and the legend's column, the text in the built-in DejaVu
/// Sans so that it reads the same on a machine without fonts.
///
/// # Errors
/// What the PNG encoder returns (writing into memory, it has no reason to fail).
pub fn xy_chart_png(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[XySeries],
) -> image::ImageResult<Vec<u8>> {
    use image::ImageEncoder;
    let (w, h) = chart_size(series, PNG_SCALE);
    let mut rgb = vec![0u8; 3 * w as usize * h as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        draw_chart(&root, PNG_SCALE, title, x_label, y_label, series);
        let _ = root.present();
    }
    let mut png = Vec::new();
    // The default deflate: on a chart of eight curves 40 % smaller than the fast one (125 kB
    // against 206 kB) for some 15 ms more; the best is no smaller and takes 3 times as long.
    image::codecs::png::PngEncoder::new_with_quality(
        &mut png,
        image::codecs::png::CompressionType::Default,
        image::codecs::png::FilterType::Adaptive,
    )
    .write_image(&rgb, w, h, image::ExtendedColorType::Rgb8)?;
    Ok(png)
}

/// The chart's size at `scale`: the data area and the legend's column, as wide as its longest
/// name.
fn chart_size(series: &[XySeries], scale: u32) -> (u32, u32) {
    let legend_width = series
        .iter()
        .map(|s| s.name.chars().count())
        .max()
        .map_or(0, |n| 44 + 9 * n as u32);
    (scale * (W + legend_width), scale * H)
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

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// The whole chart on `root`, every length `scale` times its size in the SVG. Drawing into a
/// string or a buffer of the right size cannot fail; a chart that could not be laid out is
/// left empty.
fn draw_chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scale: u32,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[XySeries],
) {
    register_built_in_font();
    let _ = draw_xy(root, scale, title, x_label, y_label, series);
    let _ = draw_legend(root, scale, series);
}

/// The x and y ranges drawn: the finite points' x range, the y range of [`y_range`]; 0 to 1
/// without a finite point.
fn data_ranges(series: &[XySeries]) -> ((f64, f64), (f64, f64)) {
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
    ((x0, x1), y_range(y0, y1))
}

fn draw_xy<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scale: u32,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[XySeries],
) -> DrawResult<DB> {
    let ((x0, x1), (y0, y1)) = data_ranges(series);
    let s = scale;
    let text = |size: u32| (FAMILY, f64::from(s * size));
    root.fill(&WHITE)?;
    let (area, _) = root.split_horizontally(s * W);
    let mut chart = ChartBuilder::on(&area)
        .caption(title, text(19))
        .margin(s * 10)
        .x_label_area_size(s * 48)
        .y_label_area_size(s * if y_label.is_empty() { 56 } else { 76 })
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_labels(8)
        .y_labels(6)
        .label_style(text(15))
        .axis_desc_style(text(15))
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(205, 205, 205).stroke_width(s))
        .axis_style(BLACK.stroke_width(s))
        .set_all_tick_mark_size(5 * s)
        .draw()?;
    for (k, se) in series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        // A non-finite point lifts the pen: each finite run is its own line.
        for run in se
            .points
            .split(|(x, y)| !(x.is_finite() && y.is_finite()))
            .filter(|r| !r.is_empty())
        {
            chart.draw_series(LineSeries::new(
                run.iter().copied(),
                color.stroke_width(2 * s),
            ))?;
            if se.markers {
                chart.draw_series(
                    run.iter()
                        .map(|&p| Circle::new(p, 3 * s as i32, color.filled())),
                )?;
            }
        }
    }
    Ok(())
}

/// The legend in its own column right of the chart: a colour swatch and the whole name.
fn draw_legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scale: u32,
    series: &[XySeries],
) -> DrawResult<DB> {
    let s = scale as i32;
    let font = (FAMILY, f64::from(15 * scale)).into_font().color(&BLACK);
    for (k, se) in series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let y = s * (44 + 22 * k as i32);
        let x = s * (W as i32 + 8);
        root.draw(&PathElement::new(
            vec![(x, y), (x + s * 22, y)],
            color.stroke_width(3 * scale),
        ))?;
        root.draw(&Text::new(
            se.name.clone(),
            (x + s * 28, y - s * 9),
            font.clone(),
        ))?;
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
    fn a_png_decodes_at_twice_the_svgs_size_with_its_text_drawn() {
        let series = [XySeries {
            name: "jawOpen".into(),
            points: (0..60)
                .map(|i| (i as f64 / 30.0, (i as f64 / 6.0).sin()))
                .collect(),
            markers: true,
        }];
        let decode = |title: &str| {
            let png = xy_chart_png(title, "time (s)", "weight", &series).unwrap();
            image::load_from_memory_with_format(&png, image::ImageFormat::Png)
                .unwrap()
                .to_rgb8()
        };
        let image = decode("Frames per second");
        let width = 2 * (W + 44 + 9 * "jawOpen".len() as u32);
        assert_eq!(image.dimensions(), (width, 2 * H));
        // White, the grid's grey, black, the curve's colour and the glyphs' anti-aliased edges.
        let colours: std::collections::HashSet<[u8; 3]> = image.pixels().map(|p| p.0).collect();
        assert!(colours.len() > 20, "{} colours", colours.len());
        let dark = |image: &image::RgbImage, (x0, x1): (u32, u32), (y0, y1): (u32, u32)| {
            (x0..x1)
                .flat_map(|x| (y0..y1).map(move |y| (x, y)))
                .filter(|&(x, y)| image.get_pixel(x, y).0.iter().all(|&c| c < 96))
                .count()
        };
        // The title in the band over the data, the legend's name beside it: text is drawn.
        let title_band = ((0, 2 * W), (0, 60));
        assert!(dark(&image, title_band.0, title_band.1) > 200, "no title");
        assert!(
            dark(&image, (2 * W + 60, width), (60, 110)) > 100,
            "no name"
        );
        assert_eq!(dark(&decode(""), title_band.0, title_band.1), 0);
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
