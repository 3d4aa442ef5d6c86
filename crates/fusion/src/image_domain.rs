//! The fixed image-plane domain of `visage run --mesh image` (the paper's design, §4): the
//! face mask of the first frame with a face, dilated so the head can move inside it.
//!
//! The paper meshes the pixels valid in the sequence; a streaming run cannot look ahead, so
//! the domain is taken from the first frame: its rendered face mask grown by
//! [`DILATION_FRACTION`] of the face box's larger side (a square structuring element, two
//! separable passes). Pixels of later frames outside the face are holes (filled by the
//! previous solution, `Fuser::process`).

use visage_camera::DepthMap;
use visage_mesh::Mask;

/// Dilation of the first frame's face mask, as a fraction of the face box's larger side.
pub const DILATION_FRACTION: f64 = 0.15;

/// The face mask of `face_depth` (valid pixels) dilated by `radius` pixels (square element).
pub fn dilated_face_mask(face_depth: &DepthMap, radius: usize) -> Mask {
    let (w, h) = (face_depth.width as usize, face_depth.height as usize);
    let mask: Vec<bool> = face_depth
        .data
        .iter()
        .map(|&d| DepthMap::is_valid(d))
        .collect();
    let rows = dilate_lines(&mask, w, h, radius, 1, w);
    let both = dilate_lines(&rows, h, w, radius, w, 1);
    Mask {
        width: face_depth.width,
        height: face_depth.height,
        data: both,
    }
}

/// The dilation radius for a face box `[x, y, w, h]` (pixels).
pub fn dilation_radius(face_box: [f32; 4]) -> usize {
    (DILATION_FRACTION * face_box[2].max(face_box[3]).max(0.0) as f64).ceil() as usize
}

/// 1-D dilation along lines: `lines` lines of `len` pixels, consecutive pixels `step` apart,
/// consecutive lines `line_step` apart. A running count over the window keeps it O(pixels).
fn dilate_lines(
    mask: &[bool],
    len: usize,
    lines: usize,
    radius: usize,
    step: usize,
    line_step: usize,
) -> Vec<bool> {
    let mut out = vec![false; mask.len()];
    for line in 0..lines {
        let at = |i: usize| line * line_step + i * step;
        let mut count = (0..radius.min(len)).filter(|&i| mask[at(i)]).count();
        for i in 0..len {
            if i + radius < len && mask[at(i + radius)] {
                count += 1;
            }
            if i > radius && mask[at(i - radius - 1)] {
                count -= 1;
            }
            out[at(i)] = count > 0;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use visage_camera::DepthKind;

    #[test]
    fn one_pixel_grows_into_a_square() {
        let mut d = DepthMap::empty(9, 7, DepthKind::Z);
        d.data[3 * 9 + 4] = 1.0;
        let m = dilated_face_mask(&d, 2);
        for v in 0..7i64 {
            for u in 0..9i64 {
                let inside = (u - 4).abs() <= 2 && (v - 3).abs() <= 2;
                assert_eq!(m.get(u, v), inside, "({u}, {v})");
            }
        }
        assert_eq!(dilated_face_mask(&d, 0).count(), 1);
        assert_eq!(dilation_radius([0.0, 0.0, 100.0, 60.0]), 15);
    }
}
