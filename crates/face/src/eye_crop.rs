//! The iris network's input: an axis-aligned square around one eye, sampled from the frame.
//!
//! As `shared/reference/facemesh/README.md` ("Eyes") describes it: centred on the midpoint of
//! the eye's corners (FaceMesh landmarks 33/133 for the subject's right eye, 362/263 for the
//! left), side 2.3 × the corner distance, bilinear, and the left eye's crop mirrored
//! horizontally so that both eyes look like a right eye to the network.

use image::RgbImage;

use crate::IRIS_INPUT;
use visage_nn::bilinear::sample_rgb_lanes;

/// Side of the eye crop divided by the distance between the eye's corners.
pub const EYE_CROP_SCALE: f32 = 2.3;

/// One of the subject's eyes, named as MediaPipe names them: the subject's **right** eye
/// (landmarks 33/133) appears on the **left** of an unmirrored image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Eye {
    /// The subject's right eye (image left): corners 33 (outer) and 133 (inner).
    Right,
    /// The subject's left eye (image right): corners 362 (inner) and 263 (outer); its crop is
    /// mirrored.
    Left,
}

impl Eye {
    /// Both eyes, right first (MediaPipe's order: right iris 468–472, left iris 473–477).
    pub const BOTH: [Eye; 2] = [Eye::Right, Eye::Left];

    /// The FaceMesh landmarks of the eye's corners, image-left one first.
    pub fn corners(self) -> [usize; 2] {
        match self {
            Eye::Right => [33, 133],
            Eye::Left => [362, 263],
        }
    }

    /// Whether the eye's crop is mirrored horizontally before the network sees it.
    pub fn mirrored(self) -> bool {
        self == Eye::Left
    }
}

/// Where an eye crop lies in the frame: crop pixel `(x, y)` (`x, y ∈ [0, 64]`, left/top edge at
/// 0) is frame point `(x0 + scale·x, y0 + scale·y)`, or `(x0 + scale·(64 − x), …)` when
/// mirrored — in MediaPipe's pixel convention (visage's + ½), like [`crate::Roi`], and exactly
/// the `crop_to_frame` of `shared/reference/facemesh/*/iris_raw_*.json`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeCrop {
    /// Frame x of the crop's `x = 0` (unmirrored: its left edge; mirrored: the point the
    /// crop's right edge maps to), MediaPipe convention.
    pub x0: f32,
    /// Frame y of the crop's top edge, MediaPipe convention.
    pub y0: f32,
    /// Frame pixels per crop pixel.
    pub scale: f32,
    /// Whether the crop is mirrored horizontally (the subject's left eye).
    pub mirrored: bool,
}

impl EyeCrop {
    /// The crop of `eye` from 468 (or more) FaceMesh landmarks in frame pixels, visage
    /// convention. `None` if there are too few points or the corners coincide or are not finite.
    pub fn from_landmarks(points: &[[f32; 3]], eye: Eye) -> Option<EyeCrop> {
        let [a, b] = eye.corners().map(|i| points.get(i));
        let (a, b) = (a?, b?);
        let distance = (a[0] - b[0]).hypot(a[1] - b[1]);
        let side = EYE_CROP_SCALE * distance;
        let crop = EyeCrop {
            x0: 0.5 * (a[0] + b[0]) + 0.5 - 0.5 * side,
            y0: 0.5 * (a[1] + b[1]) + 0.5 - 0.5 * side,
            scale: side / IRIS_INPUT as f32,
            mirrored: eye.mirrored(),
        };
        (crop.x0.is_finite() && crop.y0.is_finite() && crop.scale.is_finite() && crop.scale > 0.0)
            .then_some(crop)
    }

    /// Frame x (MediaPipe convention) of crop x.
    fn frame_x(&self, x: f32) -> f32 {
        let x = if self.mirrored {
            IRIS_INPUT as f32 - x
        } else {
            x
        };
        self.x0 + self.scale * x
    }

    /// A network output point (crop pixels) in frame pixels, visage convention (centre of pixel
    /// `(i, j)` at `(i, j)`); `z` is scaled like `x` (relative depth, frame pixels).
    pub fn to_frame(&self, p: [f32; 3]) -> [f32; 3] {
        [
            self.frame_x(p[0]) - 0.5,
            self.y0 + self.scale * p[1] - 0.5,
            p[2] * self.scale,
        ]
    }

    /// Fills `out` (`64 × 64 × 3`, row-major RGB) with the crop, values `pixel / 255`.
    ///
    /// Output pixel `(i, j)` samples the frame at `(x0 + scale·i, y0 + scale·j)` (mirrored:
    /// `x0 + scale·(64 − i)`) read as pixel-centre coordinates, bilinearly, coordinates clamped
    /// to the image (replicated border). This is OpenCV's `warpAffine` with `INTER_LINEAR` on
    /// the crop-to-frame map, as the reference crops were made (and as [`crate::crop`] samples
    /// the face ROI); OpenCV rounds the sample positions to 1/32 pixel, which explains the
    /// remaining difference (mean 0.2–0.3 of 255 levels per channel).
    ///
    /// # Panics
    /// If `out.len() != 64 · 64 · 3` or the image is empty.
    #[track_caller]
    pub fn sample(&self, image: &RgbImage, out: &mut [f32]) {
        let side = IRIS_INPUT;
        assert_eq!(out.len(), side * side * 3, "eye crop buffer size");
        let (w, h) = (image.width() as usize, image.height() as usize);
        assert!(w > 0 && h > 0, "empty image");
        let src = image.as_raw();
        let (max_x, max_y) = ((w - 1) as f32, (h - 1) as f32);
        // The input's side is a multiple of eight: eight pixels at a time.
        const _: () = assert!(IRIS_INPUT.is_multiple_of(8));
        for (j, row) in out.chunks_exact_mut(side * 3).enumerate() {
            let fy = [(self.y0 + self.scale * j as f32).clamp(0.0, max_y); 8];
            for (k, o) in row.chunks_exact_mut(24).enumerate() {
                let fx: [f32; 8] =
                    std::array::from_fn(|q| self.frame_x((8 * k + q) as f32).clamp(0.0, max_x));
                let o: &mut [f32; 24] = o.try_into().expect("24 values");
                sample_rgb_lanes(src, w, h, &fx, &fy, o);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn landmarks_with(eye: Eye, a: [f32; 2], b: [f32; 2]) -> Vec<[f32; 3]> {
        let mut points = vec![[0.0; 3]; 468];
        let [i, j] = eye.corners();
        points[i] = [a[0], a[1], 0.0];
        points[j] = [b[0], b[1], 0.0];
        points
    }

    #[test]
    fn crop_is_centred_on_the_corners_and_maps_back() {
        // Corners 20 px apart around (99.5, 49.5) (visage) = (100, 50) (MediaPipe).
        let points = landmarks_with(Eye::Right, [89.5, 49.5], [109.5, 49.5]);
        let crop = EyeCrop::from_landmarks(&points, Eye::Right).unwrap();
        assert!((crop.scale - 46.0 / 64.0).abs() < 1e-6);
        assert!((crop.x0 - 77.0).abs() < 1e-4 && (crop.y0 - 27.0).abs() < 1e-4);
        // The crop's centre maps to the corners' midpoint.
        let c = crop.to_frame([32.0, 32.0, 1.0]);
        assert!((c[0] - 99.5).abs() < 1e-4 && (c[1] - 49.5).abs() < 1e-4);
        assert!((c[2] - 46.0 / 64.0).abs() < 1e-6);
        // Mirrored: crop x and 64 − x swap sides around the same centre.
        let points = landmarks_with(Eye::Left, [89.5, 49.5], [109.5, 49.5]);
        let left = EyeCrop::from_landmarks(&points, Eye::Left).unwrap();
        assert!(left.mirrored);
        let p = left.to_frame([10.0, 32.0, 0.0]);
        let q = crop.to_frame([54.0, 32.0, 0.0]);
        assert!((p[0] - q[0]).abs() < 1e-4 && (p[1] - q[1]).abs() < 1e-4);
    }

    #[test]
    fn degenerate_landmarks_give_no_crop() {
        let points = landmarks_with(Eye::Right, [5.0, 5.0], [5.0, 5.0]);
        assert!(EyeCrop::from_landmarks(&points, Eye::Right).is_none());
        assert!(EyeCrop::from_landmarks(&points[..200], Eye::Right).is_none());
        let points = landmarks_with(Eye::Left, [f32::NAN, 5.0], [9.0, 5.0]);
        assert!(EyeCrop::from_landmarks(&points, Eye::Left).is_none());
    }

    #[test]
    fn mirrored_crop_samples_the_image_flipped() {
        // A horizontal ramp: at scale 1 output pixel i samples frame x0 + i (or x0 + 64 − i).
        let img = RgbImage::from_fn(200, 100, |x, _| image::Rgb([x as u8, 0, 9]));
        let plain = EyeCrop {
            x0: 10.0,
            y0: 5.0,
            scale: 1.0,
            mirrored: false,
        };
        let mirrored = EyeCrop {
            mirrored: true,
            ..plain
        };
        let (mut a, mut b) = (vec![0.0; 64 * 64 * 3], vec![0.0; 64 * 64 * 3]);
        plain.sample(&img, &mut a);
        mirrored.sample(&img, &mut b);
        for i in 0..64 {
            assert!((a[i * 3] * 255.0 - (10 + i) as f32).abs() < 1e-3);
            assert!((b[i * 3] * 255.0 - (74 - i) as f32).abs() < 1e-3);
            assert!((a[i * 3 + 2] * 255.0 - 9.0).abs() < 1e-3);
        }
    }
}
