use std::io::Cursor;
use std::path::Path;

use image::error::ImageFormatHint;
use image::{DynamicImage, ImageBuffer, ImageError, ImageFormat, Luma};

use crate::{CameraError, DepthKind, DepthMap};

/// Reads a 16-bit single-channel PNG depth image: metres = value / `scale`, 0 = no data.
///
/// Any other pixel format (8-bit, RGB, …) is an error that names the file and the format found.
pub fn read_depth_png(path: &Path, scale: f64, kind: DepthKind) -> Result<DepthMap, CameraError> {
    let bytes = std::fs::read(path).map_err(|source| CameraError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse_depth_png(&bytes, path, scale, kind)
}

/// [`read_depth_png`] of a file's bytes already in memory; `path` is the file they came from,
/// named in errors (its extension is the format's fallback when the content does not tell it).
pub fn parse_depth_png(
    bytes: &[u8],
    path: &Path,
    scale: f64,
    kind: DepthKind,
) -> Result<DepthMap, CameraError> {
    let bad = |reason: String| CameraError::DepthImage {
        path: path.to_owned(),
        reason,
    };
    let cannot_decode = |e: ImageError| bad(format!("cannot decode image: {e}"));
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|source| CameraError::Io {
            path: path.to_owned(),
            source,
        })?;
    // As `ImageReader::open` does: when the content does not tell the format, the extension does.
    if reader.format().is_none() {
        if let Some(ext) = path.extension().filter(|ext| !ext.is_empty()) {
            let format = ImageFormat::from_extension(ext).ok_or_else(|| {
                cannot_decode(ImageError::Unsupported(
                    ImageFormatHint::PathExtension(ext.into()).into(),
                ))
            })?;
            reader.set_format(format);
        }
    }
    let img = reader.decode().map_err(cannot_decode)?;
    let DynamicImage::ImageLuma16(buf) = img else {
        return Err(bad(format!(
            "expected a 16-bit single-channel depth PNG, found {:?}",
            img.color()
        )));
    };
    let inv = 1.0 / scale;
    Ok(DepthMap {
        width: buf.width(),
        height: buf.height(),
        kind,
        data: buf
            .as_raw()
            .iter()
            .map(|&v| (v as f64 * inv) as f32)
            .collect(),
    })
}

/// Writes a depth map as 16-bit PNG with value = round(metres · `scale`), 0 for invalid pixels
/// and values clamped to 65535.
pub fn write_depth_png(path: &Path, depth: &DepthMap, scale: f64) -> Result<(), CameraError> {
    let pixels: Vec<u16> = depth
        .data
        .iter()
        .map(|&d| {
            if DepthMap::is_valid(d) {
                (d as f64 * scale).round().clamp(0.0, u16::MAX as f64) as u16
            } else {
                0
            }
        })
        .collect();
    let buf: ImageBuffer<Luma<u16>, Vec<u16>> =
        ImageBuffer::from_raw(depth.width, depth.height, pixels).ok_or_else(|| {
            CameraError::DepthImage {
                path: path.to_owned(),
                reason: "pixel count does not match the image size".into(),
            }
        })?;
    buf.save(path).map_err(|e| CameraError::DepthImage {
        path: path.to_owned(),
        reason: format!("cannot write PNG: {e}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_in_millimetres() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("d.png");
        let mut d = DepthMap::empty(3, 2, DepthKind::Z);
        d.data = vec![0.0, 0.5, 1.2345, f32::NAN, 65.0, 70.0];
        write_depth_png(&path, &d, 1000.0).unwrap();
        let back = read_depth_png(&path, 1000.0, DepthKind::Z).unwrap();
        assert_eq!(back.data[0], 0.0);
        assert!((back.data[1] - 0.5).abs() < 1e-6);
        assert!((back.data[2] - 1.235).abs() < 1e-6);
        assert_eq!(back.data[3], 0.0);
        assert!((back.data[5] - 65.535).abs() < 1e-4, "clamped");
    }

    #[test]
    fn eight_bit_png_is_rejected_with_the_file_name() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("eight.png");
        image::GrayImage::new(2, 2).save(&path).unwrap();
        let err = read_depth_png(&path, 1000.0, DepthKind::Z)
            .unwrap_err()
            .to_string();
        assert!(err.contains("eight.png") && err.contains("16-bit"), "{err}");
    }
}
