//! Shot cuts: where the temporal model must forget the past. A frame starts a new shot when
//! its picture changes abruptly (the mean absolute difference of 32 × 32 grey thumbnails of
//! consecutive frames, each less its mean, so that a flash or an exposure change is not a
//! cut), when, seen by the tracker, the face jumps (its landmarks move by more than a fraction
//! of the face's size in one frame), or when the face itself changes — another person filmed
//! alike, in the same place against the same background, where the whole picture barely
//! changes: the 16 × 16 grey thumbnail of the landmarks' box, less its mean and over its
//! standard deviation, differs from the previous frame's by more than [`CUT_FACE_CHANGE`]. At a
//! cut the tracker looks for the face afresh, and the landmark filter, the model fit's track
//! and the fusion's temporal term restart (μ = 0 for that frame, on the matrix already factored
//! for it).

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

/// A face thumbnail difference (mean absolute, in units of the thumbnail's own standard
/// deviation) above this is another face. Within a shot, frame to frame, the shared clips stay
/// below 0.34 (lp_d13; lp_d18 0.24: talking, turning, blinking) and renders of a performer's
/// whole range of expressions below 0.23; two people filmed alike, one after the other,
/// differ by 0.99. The threshold sits between, 1.8 times the largest change within a shot.
pub const CUT_FACE_CHANGE: f64 = 0.6;

/// Face thumbnail side, cells.
const FACE_THUMB: usize = 16;

/// The picture thumbnail samples every second pixel of every second row up to this many pixels
/// on the frame's longer side, and proportionally fewer beyond (every fourth up to twice this,
/// …), so that a 4K frame costs about what a 1080p one does.
const PICTURE_SAMPLING_SIDE: usize = 1920;

/// The same for the face thumbnail and the longer side of the landmarks' box.
const FACE_SAMPLING_SIDE: usize = 1024;

/// The sampling step (pixels, in both directions) over an extent whose longer side is `side`:
/// 2, or more for a side over `limit` (an even step, so that the sampled grid stays that of
/// every second pixel, thinned).
fn sampling_step(side: usize, limit: usize) -> usize {
    2 * side.div_ceil(limit).max(1)
}

/// Watches consecutive frames for cuts.
#[derive(Default)]
pub struct CutDetector {
    previous: Option<Vec<f32>>,
    scratch: Vec<f32>,
    /// The previous frame's face thumbnail, when it had a face.
    previous_face: Option<Vec<f32>>,
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

impl CutDetector {
    /// Whether the face in `frame`, within its landmarks' box (`landmarks_px`; empty: no
    /// face), is another than the previous frame's ([`CUT_FACE_CHANGE`]); never when either
    /// frame has no face.
    pub fn face_cut(&mut self, frame: &RgbImage, landmarks_px: &[[f64; 2]]) -> bool {
        let Some(current) = face_thumbnail(frame, landmarks_px) else {
            self.previous_face = None;
            return false;
        };
        let cut = self.previous_face.as_ref().is_some_and(|prev| {
            let change = prev
                .iter()
                .zip(&current)
                .map(|(a, b)| (a - b).abs() as f64)
                .sum::<f64>()
                / prev.len() as f64;
            change > CUT_FACE_CHANGE
        });
        self.previous_face = Some(current);
        cut
    }
}

/// The grey thumbnail of the landmarks' box: [`FACE_THUMB`]² cells, each the mean grey of
/// every second pixel of every second row in it (sparser in a box over [`FACE_SAMPLING_SIDE`]), less the cells' mean and over their standard deviation
/// (so that light and contrast changes are not another face). `None` without landmarks or for
/// a box under two pixels per cell.
fn face_thumbnail(frame: &RgbImage, landmarks_px: &[[f64; 2]]) -> Option<Vec<f32>> {
    let (w, h) = (frame.width() as f64, frame.height() as f64);
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in landmarks_px {
        for c in 0..2 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    let (x0, y0) = (lo[0].max(0.0).floor(), lo[1].max(0.0).floor());
    let (x1, y1) = (hi[0].min(w).ceil(), hi[1].min(h).ceil());
    let n = FACE_THUMB as f64;
    if !(x1 - x0 >= 2.0 * n && y1 - y0 >= 2.0 * n) {
        return None;
    }
    let (x0, y0, x1, y1) = (x0 as usize, y0 as usize, x1 as usize, y1 as usize);
    let step = sampling_step((x1 - x0).max(y1 - y0), FACE_SAMPLING_SIDE);
    let mut sums = [0u64; FACE_THUMB * FACE_THUMB];
    let mut counts = [0u32; FACE_THUMB * FACE_THUMB];
    let raw = frame.as_raw();
    let stride = frame.width() as usize * 3;
    for y in (y0..y1).step_by(step) {
        let cy = (y - y0) * FACE_THUMB / (y1 - y0);
        for x in (x0..x1).step_by(step) {
            let cell = cy * FACE_THUMB + (x - x0) * FACE_THUMB / (x1 - x0);
            let p = &raw[y * stride + x * 3..y * stride + x * 3 + 3];
            sums[cell] +=
                u64::from(299 * u32::from(p[0]) + 587 * u32::from(p[1]) + 114 * u32::from(p[2]));
            counts[cell] += 1;
        }
    }
    let mut out: Vec<f32> = sums
        .iter()
        .zip(&counts)
        .map(|(&s, &c)| (s as f64 / (f64::from(c.max(1)) * 255_000.0)) as f32)
        .collect();
    let mean = out.iter().sum::<f32>() / out.len() as f32;
    let sd = (out.iter().map(|v| (v - mean) * (v - mean)).sum::<f32>() / out.len() as f32).sqrt();
    out.iter_mut().for_each(|v| *v = (*v - mean) / (sd + 1e-3));
    Some(out)
}

/// Whether the face jumped between two frames' landmarks (pixels).
pub fn face_jumped(previous: &[[f64; 2]], current: &[[f64; 2]]) -> bool {
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

/// Mean grey level (0–1, Rec. 601 weights) of each of 32 × 32 cells, from every second pixel
/// of every second row (sparser in a frame over [`PICTURE_SAMPLING_SIDE`]: [`sampling_step`]),
/// less the mean of the cells.
fn thumbnail(frame: &RgbImage, out: &mut Vec<f32>) {
    let (w, h) = (frame.width() as usize, frame.height() as usize);
    let step = sampling_step(w.max(h), PICTURE_SAMPLING_SIDE);
    // Integer sums of 299·R + 587·G + 114·B per cell (exact; a 16384² frame's largest cell sum
    // is below 2^40), a division only per cell.
    let mut sums = [0u64; THUMB * THUMB];
    let mut counts = [0u32; THUMB * THUMB];
    // The sampled columns of each cell, as runs, so that the inner loop has no division.
    let mut runs: Vec<(usize, usize, usize)> = Vec::with_capacity(THUMB);
    for x in (0..w).step_by(step) {
        let cx = x * THUMB / w;
        match runs.last_mut() {
            Some((c, _, end)) if *c == cx => *end = (x + step).min(w),
            _ => runs.push((cx, x, (x + step).min(w))),
        }
    }
    let raw = frame.as_raw();
    for y in (0..h).step_by(step) {
        let cy = y * THUMB / h;
        let row = &raw[y * w * 3..(y + 1) * w * 3];
        for &(cx, x0, x1) in &runs {
            let cell = cy * THUMB + cx;
            let sum: u32 = row[x0 * 3..x1 * 3]
                .chunks(3 * step)
                .map(|p| 299 * u32::from(p[0]) + 587 * u32::from(p[1]) + 114 * u32::from(p[2]))
                .sum();
            sums[cell] += u64::from(sum);
            counts[cell] += (x1 - x0).div_ceil(step) as u32;
        }
    }
    out.clear();
    out.extend(
        sums.iter()
            .zip(&counts)
            .map(|(&s, &n)| (s as f64 / (f64::from(n.max(1)) * 255_000.0)) as f32),
    );
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

    /// Another face in the same box is a cut; the same face a little brighter, moved by a
    /// pixel or with its contrast halved is not; a frame without a face breaks the comparison.
    #[test]
    fn another_face_in_the_same_place_is_a_cut() {
        let face =
            |f: fn(u32, u32) -> u8| RgbImage::from_fn(80, 80, move |x, y| image::Rgb([f(x, y); 3]));
        let one = face(|x, y| ((x * 3 + y * 5) % 200) as u8 + 20);
        let brighter = face(|x, y| ((x * 3 + y * 5) % 200) as u8 + 40);
        let flatter = face(|x, y| ((x * 3 + y * 5) % 200) as u8 / 2 + 60);
        let other = face(|x, y| if (x / 10 + y / 10) % 2 == 0 { 200 } else { 40 });
        let box_px = [[10.0, 10.0], [70.0, 70.0]];
        let mut d = CutDetector::default();
        assert!(!d.face_cut(&one, &box_px));
        assert!(!d.face_cut(&brighter, &box_px));
        assert!(!d.face_cut(&flatter, &box_px));
        assert!(d.face_cut(&other, &box_px));
        assert!(!d.face_cut(&one, &[]));
        assert!(!d.face_cut(&other, &box_px));
    }

    /// The thumbnail is the definition: each cell's mean grey of every second pixel of every
    /// second row — every fourth beyond 1920 pixels, … — (computed here pixel by pixel in f64),
    /// less the cells' mean.
    #[test]
    fn the_thumbnail_is_the_mean_grey_of_every_second_pixel() {
        for (w, h) in [
            (64, 48),
            (37, 29),
            (1280, 720),
            (33, 3),
            (2160, 3840),
            (3001, 7),
        ] {
            let step = sampling_step(w.max(h) as usize, PICTURE_SAMPLING_SIDE);
            let frame = RgbImage::from_fn(w, h, |x, y| {
                image::Rgb([(x * 7 + y) as u8, (y * 13) as u8, (x ^ y) as u8])
            });
            let (w, h) = (w as usize, h as usize);
            let mut expected = vec![0.0f64; THUMB * THUMB];
            let mut counts = vec![0u32; THUMB * THUMB];
            let raw = frame.as_raw();
            for y in (0..h).step_by(step) {
                for x in (0..w).step_by(step) {
                    let cell = (y * THUMB / h) * THUMB + x * THUMB / w;
                    let p = &raw[(y * w + x) * 3..];
                    expected[cell] +=
                        (0.299 * p[0] as f64 + 0.587 * p[1] as f64 + 0.114 * p[2] as f64) / 255.0;
                    counts[cell] += 1;
                }
            }
            for (v, &n) in expected.iter_mut().zip(&counts) {
                *v /= n.max(1) as f64;
            }
            let mean = expected.iter().sum::<f64>() / expected.len() as f64;
            let mut got = Vec::new();
            thumbnail(&frame, &mut got);
            for (a, b) in got.iter().zip(&expected) {
                assert!(
                    (*a as f64 - (b - mean)).abs() < 1e-6,
                    "{w}×{h}: {a} vs {}",
                    b - mean
                );
            }
        }
    }

    /// Frames up to 1920 pixels (the shared clips among them) are sampled as they always were;
    /// a 4K frame at every fourth pixel, and its thumbnail stays within a small fraction of the
    /// cut threshold of the every-second-pixel one.
    #[test]
    fn a_4k_frame_is_sampled_more_sparsely_and_reads_the_same() {
        assert_eq!(sampling_step(480, PICTURE_SAMPLING_SIDE), 2);
        assert_eq!(sampling_step(1280, PICTURE_SAMPLING_SIDE), 2);
        assert_eq!(sampling_step(1920, PICTURE_SAMPLING_SIDE), 2);
        assert_eq!(sampling_step(3840, PICTURE_SAMPLING_SIDE), 4);
        assert_eq!(sampling_step(1024, FACE_SAMPLING_SIDE), 2);
        assert_eq!(sampling_step(1500, FACE_SAMPLING_SIDE), 4);
        let frame = RgbImage::from_fn(2160, 3840, |x, y| {
            let v = 128.0 + 60.0 * ((x as f64 / 97.0).sin() + (y as f64 / 131.0).cos());
            image::Rgb([v as u8, (v * 0.8) as u8, (255.0 - v) as u8])
        });
        let mut sparse = Vec::new();
        thumbnail(&frame, &mut sparse);
        let (w, h) = (2160, 3840);
        let mut dense = vec![0.0f64; THUMB * THUMB];
        let mut counts = vec![0u32; THUMB * THUMB];
        for y in (0..h).step_by(2) {
            for x in (0..w).step_by(2) {
                let p = frame.get_pixel(x as u32, y as u32).0;
                dense[(y * THUMB / h) * THUMB + x * THUMB / w] +=
                    (0.299 * p[0] as f64 + 0.587 * p[1] as f64 + 0.114 * p[2] as f64) / 255.0;
                counts[(y * THUMB / h) * THUMB + x * THUMB / w] += 1;
            }
        }
        dense
            .iter_mut()
            .zip(&counts)
            .for_each(|(v, &n)| *v /= n as f64);
        let mean = dense.iter().sum::<f64>() / dense.len() as f64;
        let change = sparse
            .iter()
            .zip(&dense)
            .map(|(a, b)| (*a as f64 - (b - mean)).abs())
            .sum::<f64>()
            / dense.len() as f64;
        assert!(change < 0.05 * CUT_PICTURE_CHANGE, "{change}");
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
