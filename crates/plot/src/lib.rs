//! The benchmark's and the run report's charts: line and x–y charts drawn with `plotters`
//! (ticks, a grid, the legend beside the data) as SVG or PNG, the PNG's text in a font built
//! into the program, and a small hand-written heat map in SVG (a table of coloured cells with
//! their values, which a chart library does not make simpler).

#![forbid(unsafe_code)]

mod font;
mod heatmap;
mod xy_chart;

pub use heatmap::heatmap_svg;
pub use xy_chart::{line_chart_svg, xy_chart_png, xy_chart_svg, Series, XySeries};
