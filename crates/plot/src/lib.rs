//! The benchmark's and the run report's charts as SVG: line and x–y charts drawn with
//! `plotters` (ticks, a grid, the legend beside the data), and a small hand-written heat map
//! (a table of coloured cells with their values, which a chart library does not make simpler).

#![forbid(unsafe_code)]

mod heatmap;
mod xy_chart;

pub use heatmap::heatmap_svg;
pub use xy_chart::{line_chart_svg, xy_chart_svg, Series, XySeries};
