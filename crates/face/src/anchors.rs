//! SSD anchors of MediaPipe's face detectors (`SsdAnchorsCalculator`, aspect ratio 1,
//! `fixed_anchor_size`, anchor offset 0.5, so only the centres matter):
//! - short range (`face_detection_short_range.pbtxt`): 4 layers, strides 8, 16, 16, 16,
//!   interpolated scale aspect ratio 1. Layers of equal stride are merged, giving a 16×16 grid
//!   with 2 anchors per cell then an 8×8 grid with 6 per cell: 896 anchors;
//! - full range (`face_detection_full_range.pbtxt`): 1 layer, stride 4 on the 192×192 input,
//!   interpolated scale aspect ratio 0 (no extra anchor): a 48×48 grid with one anchor per cell,
//!   2304 anchors.
//!
//! Anchors are row-major over cells, the anchors of a cell consecutive.

/// Input side of the short-range detector, pixels.
pub const DETECTOR_INPUT: usize = 128;
/// Number of anchors of the short-range detector (= rows of its outputs).
pub const NUM_ANCHORS: usize = 896;
/// Input side of the full-range detector, pixels.
pub const FULL_RANGE_INPUT: usize = 192;
/// Number of anchors of the full-range detector.
pub const FULL_RANGE_ANCHORS: usize = 2304;

/// Anchor centres `(x, y)` of the short-range detector, normalised to its 128×128 input, in
/// output order.
pub fn blazeface_anchors() -> Vec<[f32; 2]> {
    grid_anchors(&[(16, 2), (8, 6)])
}

/// Anchor centres `(x, y)` of the full-range detector, normalised to its 192×192 input:
/// `((x + ½)/48, (y + ½)/48)`, row-major.
pub fn full_range_anchors() -> Vec<[f32; 2]> {
    grid_anchors(&[(FULL_RANGE_INPUT / 4, 1)])
}

/// Cell centres of square grids `(grid size, anchors per cell)`, one grid after the other.
fn grid_anchors(layers: &[(usize, usize)]) -> Vec<[f32; 2]> {
    let mut out = Vec::with_capacity(layers.iter().map(|(g, n)| g * g * n).sum());
    for &(grid, per_cell) in layers {
        for y in 0..grid {
            for x in 0..grid {
                let centre = [
                    (x as f32 + 0.5) / grid as f32,
                    (y as f32 + 0.5) / grid as f32,
                ];
                out.extend(std::iter::repeat_n(centre, per_cell));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout() {
        let a = blazeface_anchors();
        assert_eq!(a.len(), NUM_ANCHORS);
        assert_eq!(a[0], [1.0 / 32.0, 1.0 / 32.0]);
        assert_eq!(a[1], a[0]);
        assert_eq!(a[2], [3.0 / 32.0, 1.0 / 32.0]);
        assert_eq!(a[511], [31.0 / 32.0, 31.0 / 32.0]);
        assert_eq!(a[512], [1.0 / 16.0, 1.0 / 16.0]);
        assert_eq!(a[517], a[512]);
        assert_eq!(a[895], [15.0 / 16.0, 15.0 / 16.0]);
        let f = full_range_anchors();
        assert_eq!(f.len(), FULL_RANGE_ANCHORS);
        assert_eq!(f[0], [0.5 / 48.0, 0.5 / 48.0]);
        assert_eq!(f[1], [1.5 / 48.0, 0.5 / 48.0]);
        assert_eq!(f[48], [0.5 / 48.0, 1.5 / 48.0]);
        assert_eq!(f[2303], [47.5 / 48.0, 47.5 / 48.0]);
    }
}
