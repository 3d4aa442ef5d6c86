//! The options of MediaPipe's custom operators that the engine runs (those of the attention
//! face mesh, version 2), read from their FlexBuffer maps ([`crate::flexbuffer`]) and checked:
//! the keys and types MediaPipe's attribute parsers read (TensorFlow Lite's GPU delegate,
//! `delegates/gpu/common/mediapipe/`), a missing key or one MediaPipe does not read is an
//! error, and so is a value its kernels would reject (a negative index, a non-positive size or
//! scale) or could not use (an empty subset).

use crate::flexbuffer::FlexMap;
use crate::ops::LandmarksToTransformMatrix;

/// The keys of `Landmarks2TransformMatrix`'s options (version 2).
const MATRIX_KEYS: [&str; 8] = [
    "left_rotation_idx",
    "output_height",
    "output_width",
    "right_rotation_idx",
    "scale_x",
    "scale_y",
    "subset_idxs",
    "target_rotation_radians",
];

/// The keys of `TransformTensorBilinear`'s options (version 2).
const CROP_KEYS: [&str; 2] = ["output_height", "output_width"];

/// The map in `bytes`, which must be in the `FLEXBUFFERS` format (`custom_options_format` 0)
/// and hold only keys of `known`.
fn options_map(bytes: &[u8], format: i8, known: &[&str]) -> Result<FlexMap, String> {
    if format != 0 {
        return Err(format!("format {format}, not FlexBuffers (0)"));
    }
    let map = FlexMap::parse(bytes)?;
    if let Some(key) = map.keys().find(|k| !known.contains(k)) {
        return Err(format!("unknown option {key}"));
    }
    Ok(map)
}

/// Integer option `key`, which must be present.
fn required_int(map: &FlexMap, key: &str) -> Result<i64, String> {
    map.int(key)?.ok_or_else(|| format!("no option {key}"))
}

/// Option `key` as an index (non-negative).
fn index(map: &FlexMap, key: &str) -> Result<usize, String> {
    let v = required_int(map, key)?;
    usize::try_from(v).map_err(|_| format!("{key} = {v} is negative"))
}

/// Option `key` as a size in pixels (positive, at most 2³¹ − 1 as in TFLite's shapes).
fn size(map: &FlexMap, key: &str) -> Result<usize, String> {
    let v = required_int(map, key)?;
    usize::try_from(v)
        .ok()
        .filter(|&v| v > 0 && v <= i32::MAX as usize)
        .ok_or_else(|| format!("{key} = {v} is not a positive size"))
}

/// Float option `key` (`default` when absent), which must be finite and, with `positive`,
/// above zero.
fn float(map: &FlexMap, key: &str, default: Option<f32>, positive: bool) -> Result<f32, String> {
    let v = match (map.float(key)?, default) {
        (Some(v), _) => v as f32,
        (None, Some(d)) => d,
        (None, None) => return Err(format!("no option {key}")),
    };
    if !v.is_finite() || (positive && v <= 0.0) {
        return Err(format!(
            "{key} = {v} is not a {}number",
            if positive { "positive " } else { "" }
        ));
    }
    Ok(v)
}

/// `Landmarks2TransformMatrix` version 2: `left_rotation_idx`, `right_rotation_idx`,
/// `output_height`, `output_width`, `scale_x`, `scale_y`, `subset_idxs` (MediaPipe pairs them,
/// an odd last one with itself: the box is that of all of them), and
/// `target_rotation_radians` (0 when absent, as MediaPipe reads it). Whether the indices fit
/// the landmarks is checked when the graph is compiled.
pub(crate) fn landmarks_to_transform_matrix(
    bytes: &[u8],
    format: i8,
) -> Result<LandmarksToTransformMatrix, String> {
    let map = options_map(bytes, format, &MATRIX_KEYS)?;
    let subset = map
        .ints("subset_idxs")?
        .ok_or("no option subset_idxs")?
        .iter()
        .map(|&i| usize::try_from(i).map_err(|_| format!("subset index {i} is negative")))
        .collect::<Result<Vec<_>, _>>()?;
    if subset.is_empty() {
        return Err("subset_idxs is empty".into());
    }
    Ok(LandmarksToTransformMatrix {
        left: index(&map, "left_rotation_idx")?,
        right: index(&map, "right_rotation_idx")?,
        target_rotation: float(&map, "target_rotation_radians", Some(0.0), false)?,
        output_size: [size(&map, "output_height")?, size(&map, "output_width")?],
        scale: [
            float(&map, "scale_x", None, true)?,
            float(&map, "scale_y", None, true)?,
        ],
        subset,
    })
}

/// `TransformTensorBilinear` version 2: `[output_height, output_width]` (checked against the
/// output's shape when the graph is compiled).
pub(crate) fn transform_tensor_bilinear(bytes: &[u8], format: i8) -> Result<[usize; 2], String> {
    let map = options_map(bytes, format, &CROP_KEYS)?;
    Ok([size(&map, "output_height")?, size(&map, "output_width")?])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A FlexBuffer map of one-byte keys and values (widths of one byte throughout; floats are
    /// not one byte wide, so only integers and a vector): `entries` sorted by key.
    fn small_map(entries: &[(&str, Result<i8, Vec<i8>>)]) -> Vec<u8> {
        let mut b = Vec::new();
        let mut key_at = Vec::new();
        for (k, _) in entries {
            key_at.push(b.len());
            b.extend(k.as_bytes());
            b.push(0);
        }
        let mut vector_at = Vec::new();
        for (_, v) in entries {
            if let Err(v) = v {
                b.push(v.len() as u8);
                vector_at.push(Some(b.len()));
                b.extend(v.iter().map(|&x| x as u8));
            } else {
                vector_at.push(None);
            }
        }
        b.push(entries.len() as u8);
        let keys = b.len();
        for (k, &at) in key_at.iter().enumerate() {
            b.push((keys + k - at) as u8);
        }
        let prefix = b.len();
        b.extend([(prefix - keys) as u8, 1, entries.len() as u8]);
        let map = b.len();
        for ((_, v), at) in entries.iter().zip(&vector_at) {
            let slot = b.len();
            b.push(match (v, at) {
                (Ok(x), _) => *x as u8,
                (Err(_), Some(at)) => (slot - at) as u8,
                (Err(_), None) => unreachable!("a vector has a position"),
            });
        }
        for (_, v) in entries {
            b.push(if v.is_ok() { 1 << 2 } else { 11 << 2 });
        }
        let root = b.len();
        b.extend([(root - map) as u8, 9 << 2, 1]);
        b
    }

    #[test]
    fn crop_options_are_read_and_checked() {
        let ok = small_map(&[("output_height", Ok(16)), ("output_width", Ok(8))]);
        assert_eq!(transform_tensor_bilinear(&ok, 0), Ok([16, 8]));
        assert!(transform_tensor_bilinear(&ok, 1)
            .unwrap_err()
            .contains("format 1"));
        let zero = small_map(&[("output_height", Ok(0)), ("output_width", Ok(8))]);
        assert!(transform_tensor_bilinear(&zero, 0)
            .unwrap_err()
            .contains("output_height = 0"));
        let missing = small_map(&[("output_height", Ok(16))]);
        assert!(transform_tensor_bilinear(&missing, 0)
            .unwrap_err()
            .contains("no option output_width"));
        let extra = small_map(&[
            ("align", Ok(1)),
            ("output_height", Ok(16)),
            ("output_width", Ok(8)),
        ]);
        assert!(transform_tensor_bilinear(&extra, 0)
            .unwrap_err()
            .contains("unknown option align"));
    }

    #[test]
    fn matrix_options_need_positive_scales_and_a_subset() {
        // Integer scales (read as floats), no target rotation (0).
        let map = |left: i8, subset: Vec<i8>, scale: i8| {
            small_map(&[
                ("left_rotation_idx", Ok(left)),
                ("output_height", Ok(4)),
                ("output_width", Ok(2)),
                ("right_rotation_idx", Ok(1)),
                ("scale_x", Ok(scale)),
                ("scale_y", Ok(1)),
                ("subset_idxs", Err(subset)),
            ])
        };
        let op = landmarks_to_transform_matrix(&map(0, vec![0, 1, 2], 2), 0).unwrap();
        assert_eq!(
            op,
            LandmarksToTransformMatrix {
                left: 0,
                right: 1,
                target_rotation: 0.0,
                output_size: [4, 2],
                scale: [2.0, 1.0],
                subset: vec![0, 1, 2],
            }
        );
        let e = |bytes: Vec<u8>| landmarks_to_transform_matrix(&bytes, 0).unwrap_err();
        assert!(e(map(-1, vec![0], 1)).contains("left_rotation_idx = -1 is negative"));
        assert!(e(map(0, vec![0, -2], 1)).contains("subset index -2"));
        assert!(e(map(0, vec![], 1)).contains("subset_idxs is empty"));
        assert!(e(map(0, vec![0], 0)).contains("scale_x = 0"));
        assert!(e(b"junk".to_vec()).contains("byte width"));
    }
}
