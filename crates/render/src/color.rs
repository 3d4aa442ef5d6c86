//! Colour output: linear RGB written as 8-bit sRGB PNG. The sRGB ↔ linear conversions
//! (IEC 61966-2-1) are [`visage_mesh::color`]'s, re-exported here.

use std::path::Path;

pub use visage_mesh::color::{
    linear_to_srgb, linear_to_srgb_u8, srgb_to_linear, srgb_to_linear_u8,
};

use crate::RenderError;

/// Writes a linear RGB image (`width × height`, row-major, values clamped to `[0, 1]`) as an
/// 8-bit sRGB PNG. Errors name the file.
pub fn write_srgb_png(
    path: &Path,
    width: u32,
    height: u32,
    linear: &[[f32; 3]],
) -> Result<(), RenderError> {
    let bytes: Vec<u8> = linear
        .iter()
        .flat_map(|p| p.map(linear_to_srgb_u8))
        .collect();
    let img = image::RgbImage::from_raw(width, height, bytes).ok_or_else(|| RenderError::File {
        path: path.to_owned(),
        reason: format!(
            "{} pixels do not make a {width}×{height} image",
            linear.len()
        ),
    })?;
    img.save(path).map_err(|e| RenderError::File {
        path: path.to_owned(),
        reason: format!("cannot write PNG: {e}"),
    })
}
