//! SSD anchors of BlazeFace short range (MediaPipe `SsdAnchorsCalculator` with the options of
//! `face_detection_short_range.pbtxt`: 4 layers, strides 8, 16, 16, 16, aspect ratio 1,
//! interpolated scale 1, `fixed_anchor_size`, anchor offset 0.5).
//!
//! Layers of equal stride are merged, giving a 16×16 grid with 2 anchors per cell then an 8×8 grid
//! with 6 per cell: 896 anchors, row-major over cells, anchors of a cell consecutive.

/// Input side of the detector, pixels.
pub const DETECTOR_INPUT: usize = 128;
/// Number of anchors (= rows of the detector outputs).
pub const NUM_ANCHORS: usize = 896;

/// Anchor centres `(x, y)` normalised to the 128×128 input, in output order.
pub fn blazeface_anchors() -> Vec<[f32; 2]> {
    // (grid size, anchors per cell)
    const LAYERS: [(usize, usize); 2] = [(16, 2), (8, 6)];
    let mut out = Vec::with_capacity(NUM_ANCHORS);
    for (grid, per_cell) in LAYERS {
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
    }
}
