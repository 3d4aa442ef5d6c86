//! The rotated square region of interest that the landmark network sees (MediaPipe
//! `DetectionsToRectsCalculator` + `RectTransformationCalculator` of `face_landmark`: rotation
//! from the eye line, square on the longer side, scaled 1.5×).

use crate::Detection;

/// ROI side / face box side (MediaPipe's `scale_x = scale_y = 1.5`).
pub const ROI_SCALE: f32 = 1.5;
/// Landmarks whose line gives the ROI rotation when tracking: right and left eye outer
/// corners (MediaPipe `face_landmark_landmarks_to_roi`: 33 and 263).
pub const ROTATION_LANDMARKS: [usize; 2] = [33, 263];

/// A rotated square in frame pixels (MediaPipe's convention: pixel `(i, j)` covers
/// `[i, i+1) × [j, j+1)`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roi {
    /// Centre `(x, y)`, pixels.
    pub center: [f32; 2],
    /// Side length, pixels.
    pub size: f32,
    /// Rotation in radians; the crop's x axis is the frame's x axis rotated by this angle
    /// (clockwise on screen for positive angles, since y points down).
    pub rotation: f32,
}

/// `a` wrapped into `[−π, π)`.
pub fn normalize_radians(a: f32) -> f32 {
    use std::f32::consts::PI;
    a - 2.0 * PI * ((a + PI) / (2.0 * PI)).floor()
}

/// MediaPipe's `ComputeRotation`: `target − atan2(−(y1 − y0), x1 − x0)` with target 0, i.e. the
/// angle that makes the line from `p0` (subject's right eye) to `p1` horizontal.
pub fn eye_line_rotation(p0: [f32; 2], p1: [f32; 2]) -> f32 {
    normalize_radians(-(-(p1[1] - p0[1])).atan2(p1[0] - p0[0]))
}

impl Roi {
    /// The ROI of a detection in frame pixels: box centre, rotation from keypoints 0 → 1 (the
    /// eyes), side `1.5 × max(w, h)`.
    pub fn from_detection(d: &Detection) -> Roi {
        Roi {
            center: d.center,
            size: ROI_SCALE * d.size[0].max(d.size[1]),
            rotation: eye_line_rotation(d.keypoints[0], d.keypoints[1]),
        }
    }

    /// The ROI for the next frame from this frame's landmarks (frame pixels, MediaPipe
    /// convention): axis-aligned bounding box centre, rotation from landmarks 33 → 263, side
    /// `1.5 × max(w, h)`. `None` when fewer than 264 points are given or they are not finite.
    pub fn from_landmarks(points: &[[f32; 3]]) -> Option<Roi> {
        if points.len() <= ROTATION_LANDMARKS[1]
            || points
                .iter()
                .any(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return None;
        }
        let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
        for p in points {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let a = points[ROTATION_LANDMARKS[0]];
        let b = points[ROTATION_LANDMARKS[1]];
        Some(Roi {
            center: [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])],
            size: ROI_SCALE * (hi[0] - lo[0]).max(hi[1] - lo[1]),
            rotation: eye_line_rotation([a[0], a[1]], [b[0], b[1]]),
        })
    }

    /// Maps a point of the crop, normalised to `[0, 1]²` (edges at 0 and 1), to frame pixels
    /// (MediaPipe's `LandmarkProjectionCalculator`).
    #[inline]
    pub fn to_frame(&self, u: f32, v: f32) -> [f32; 2] {
        let (x, y) = (u - 0.5, v - 0.5);
        let (s, c) = self.rotation.sin_cos();
        [
            self.center[0] + (c * x - s * y) * self.size,
            self.center[1] + (s * x + c * y) * self.size,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_levels_the_eye_line() {
        assert_eq!(eye_line_rotation([0.0, 0.0], [1.0, 0.0]), 0.0);
        // Left eye lower on screen (y down) → head rolled clockwise → positive rotation.
        let r = eye_line_rotation([0.0, 0.0], [1.0, 1.0]);
        assert!((r - std::f32::consts::FRAC_PI_4).abs() < 1e-6);
        let roi = Roi {
            center: [10.0, 20.0],
            size: 4.0,
            rotation: r,
        };
        // The crop's x axis runs along the eye line.
        let a = roi.to_frame(0.0, 0.5);
        let b = roi.to_frame(1.0, 0.5);
        assert!(((b[1] - a[1]) - (b[0] - a[0])).abs() < 1e-5 && b[0] > a[0]);
        assert_eq!(roi.to_frame(0.5, 0.5), [10.0, 20.0]);
        assert!(
            (normalize_radians(3.0 * std::f32::consts::PI) + std::f32::consts::PI).abs() < 1e-5
        );
    }

    #[test]
    fn landmark_roi_is_square_and_scaled() {
        let mut pts = vec![[0.0f32; 3]; 468];
        for (i, p) in pts.iter_mut().enumerate() {
            *p = [(i % 10) as f32, (i % 20) as f32 * 2.0, 0.0];
        }
        let roi = Roi::from_landmarks(&pts).unwrap();
        assert_eq!(roi.center, [4.5, 19.0]);
        assert_eq!(roi.size, 1.5 * 38.0);
        assert!(Roi::from_landmarks(&pts[..100]).is_none());
    }
}
