//! Shot cuts: where the temporal model must forget the past. A frame starts a new shot when
//! its picture changes abruptly (the mean absolute difference of 32 × 32 grey thumbnails of
//! consecutive frames, each less its mean, so that a flash or an exposure change is not a
//! cut) or, seen by the tracker, the face jumps (its landmarks move by more
//! than a fraction of the face's size in one frame). At a cut the tracker looks for the face
//! afresh, and the landmark filter, the model fit's track and the fusion's temporal term
//! restart (μ = 0 for that frame, on the matrix already factored for it).

use image::RgbImage;

/// Thumbnail side, cells.
const THUMB: usize = 32;

/// A thumbnail difference (mean absolute, grey levels / 255) above this is a cut. Within a
/// shot the shared clips stay below 0.0045 frame to frame; two different shots cut together
/// differ by about 0.21; a frame 30 % brighter than the one before differs by about 0.04.
pub const CUT_PICTURE_CHANGE: f64 = 0.08;

/// A mean landmark displacement above this fraction of the face's size (its landmarks' box
/// diagonal) between consecutive frames is a cut.
pub const CUT_FACE_JUMP: f64 = 0.25;

/// Watches consecutive frames for cuts.
#[derive(Default)]
pub(crate) struct CutDetector {
    previous: Option<Vec<f32>>,
    scratch: Vec<f32>,
}

impl CutDetector {
    /// Whether `frame` starts a new shot (never the first frame).
    pub fn picture_cut(&mut self, frame: &RgbImage) -> bool {
        thumbnail(frame, &mut self.scratch);
        let cut = self.previous.as_ref().is_some_and(|prev| {
            let change = prev
                .iter()
                .zip(&self.scratch)
                .map(|(a, b)| (a - b).abs() as f64)
                .sum::<f64>()
                / prev.len() as f64;
            change > CUT_PICTURE_CHANGE
        });
        match &mut self.previous {
            Some(p) => std::mem::swap(p, &mut self.scratch),
            None => self.previous = Some(self.scratch.clone()),
        }
        cut
    }
}

/// Whether the face jumped between two frames' landmarks (pixels).
pub(crate) fn face_jumped(previous: &[[f64; 2]], current: &[[f64; 2]]) -> bool {
    if previous.len() != current.len() || current.is_empty() {
        return false;
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in current {
        for c in 0..2 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    let size = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
    let moved = previous
        .iter()
        .zip(current)
        .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
        .sum::<f64>()
        / current.len() as f64;
    moved > CUT_FACE_JUMP * size
}

/// Mean grey level (0–1) of each of 32 × 32 cells, from every second pixel of every second
/// row, less the mean of the cells.
fn thumbnail(frame: &RgbImage, out: &mut Vec<f32>) {
    let (w, h) = (frame.width() as usize, frame.height() as usize);
    out.clear();
    out.resize(THUMB * THUMB, 0.0);
    let mut counts = vec![0u32; THUMB * THUMB];
    let raw = frame.as_raw();
    for y in (0..h).step_by(2) {
        let cy = y * THUMB / h;
        for x in (0..w).step_by(2) {
            let cell = cy * THUMB + x * THUMB / w;
            let p = &raw[(y * w + x) * 3..(y * w + x) * 3 + 3];
            out[cell] += (0.299 * p[0] as f32 + 0.587 * p[1] as f32 + 0.114 * p[2] as f32) / 255.0;
            counts[cell] += 1;
        }
    }
    for (v, &n) in out.iter_mut().zip(&counts) {
        *v /= n.max(1) as f32;
    }
    let mean = out.iter().sum::<f32>() / out.len() as f32;
    out.iter_mut().for_each(|v| *v -= mean);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_picture_is_a_cut_and_a_small_change_is_not() {
        let mut d = CutDetector::default();
        let dark = RgbImage::from_fn(64, 48, |x, _| image::Rgb([(x * 2) as u8; 3]));
        let nudged = RgbImage::from_fn(64, 48, |x, _| image::Rgb([(x * 2 + 3) as u8; 3]));
        let other = RgbImage::from_fn(64, 48, |_, y| image::Rgb([(255 - y * 4) as u8; 3]));
        assert!(!d.picture_cut(&dark));
        assert!(!d.picture_cut(&nudged));
        assert!(d.picture_cut(&other));
        assert!(!d.picture_cut(&other));
    }

    #[test]
    fn a_flash_is_not_a_cut() {
        let mut d = CutDetector::default();
        let frame = |gain: f32| {
            RgbImage::from_fn(64, 48, |x, y| {
                image::Rgb([((40 + x + y) as f32 * gain).min(255.0) as u8; 3])
            })
        };
        assert!(!d.picture_cut(&frame(1.0)));
        assert!(!d.picture_cut(&frame(1.3)), "30 % brighter");
        assert!(!d.picture_cut(&frame(1.0)));
    }

    #[test]
    fn a_face_jump_is_a_fraction_of_its_size() {
        let face: Vec<[f64; 2]> = (0..10).map(|i| [i as f64 * 10.0, i as f64 * 5.0]).collect();
        let near: Vec<[f64; 2]> = face.iter().map(|p| [p[0] + 5.0, p[1]]).collect();
        let far: Vec<[f64; 2]> = face.iter().map(|p| [p[0] + 60.0, p[1]]).collect();
        assert!(!face_jumped(&face, &near));
        assert!(face_jumped(&face, &far));
    }
}
