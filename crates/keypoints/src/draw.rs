//! Keypoints and matches drawn on an RGB image, for looking at what the detector found.

use crate::matches_file::MatchRecord;
use crate::Keypoint;

/// Colour of drawn keypoints (green).
pub const KEYPOINT_COLOUR: [u8; 3] = [0, 255, 64];

/// Colours of drawn matches, match `k` in `MATCH_COLOURS[k % 6]`: saturated hues.
pub const MATCH_COLOURS: [[u8; 3]; 6] = [
    [255, 64, 64],
    [255, 200, 0],
    [64, 160, 255],
    [255, 0, 255],
    [0, 230, 230],
    [255, 128, 0],
];

/// An 8-bit RGB image borrowed as `width × height` pixels, row-major, 3 bytes a pixel.
pub struct Canvas<'a> {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// The pixels.
    pub rgb: &'a mut [u8],
}

impl<'a> Canvas<'a> {
    /// Borrows `rgb` (`3 · width · height` bytes, row-major) as a canvas.
    ///
    /// # Panics
    /// If `rgb` holds another number of bytes.
    #[track_caller]
    pub fn new(width: usize, height: usize, rgb: &'a mut [u8]) -> Canvas<'a> {
        assert_eq!(
            rgb.len(),
            3 * width * height,
            "a {width} × {height} RGB canvas"
        );
        Canvas { width, height, rgb }
    }
}

impl Canvas<'_> {
    fn put(&mut self, x: isize, y: isize, colour: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            let at = 3 * (y as usize * self.width + x as usize);
            if let Some(p) = self.rgb.get_mut(at..at + 3) {
                p.copy_from_slice(&colour);
            }
        }
    }

    /// A one-pixel line from `a` to `b` (pixel coordinates, centres on integers).
    pub fn line(&mut self, a: [f32; 2], b: [f32; 2], colour: [u8; 3]) {
        let steps = (b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil().max(1.0);
        if !steps.is_finite() {
            return;
        }
        let n = steps as usize;
        for k in 0..=n {
            let t = k as f32 / steps;
            let x = a[0] + t * (b[0] - a[0]);
            let y = a[1] + t * (b[1] - a[1]);
            self.put(x.round() as isize, y.round() as isize, colour);
        }
    }

    /// A circle of `radius` pixels around `centre`.
    pub fn circle(&mut self, centre: [f32; 2], radius: f32, colour: [u8; 3]) {
        let n = ((2.0 * std::f32::consts::PI * radius).ceil() as usize).clamp(8, 4096);
        let point = |k: usize| {
            let t = k as f32 / n as f32 * std::f32::consts::TAU;
            [centre[0] + radius * t.cos(), centre[1] + radius * t.sin()]
        };
        for k in 0..n {
            self.line(point(k), point(k + 1), colour);
        }
    }

    /// Each keypoint as OpenCV's "rich" drawing: a circle of its size and a radius along its
    /// angle.
    pub fn keypoints(&mut self, keypoints: &[Keypoint], colour: [u8; 3]) {
        for k in keypoints {
            let radius = (k.size / 2.0).max(1.0);
            let centre = [k.x, k.y];
            self.circle(centre, radius, colour);
            let (sin, cos) = k.angle.to_radians().sin_cos();
            self.line(centre, [k.x + radius * cos, k.y + radius * sin], colour);
        }
    }

    /// Two images' matches on a canvas that holds the first image at the left edge and the
    /// second `b_offset_x` pixels to its right: a line per match (colours cycling through
    /// [`MATCH_COLOURS`]), then both images' keypoints in [`KEYPOINT_COLOUR`].
    pub fn matches(
        &mut self,
        a: &[Keypoint],
        b: &[Keypoint],
        matches: &[MatchRecord],
        b_offset_x: f32,
    ) {
        for (k, m) in matches.iter().enumerate() {
            let colour = MATCH_COLOURS[k % MATCH_COLOURS.len()];
            self.line(m.a_xy, [m.b_xy[0] + b_offset_x, m.b_xy[1]], colour);
        }
        let shifted: Vec<Keypoint> = b
            .iter()
            .map(|k| Keypoint {
                x: k.x + b_offset_x,
                ..*k
            })
            .collect();
        self.keypoints(a, KEYPOINT_COLOUR);
        self.keypoints(&shifted, KEYPOINT_COLOUR);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_keypoint_is_drawn_inside_the_canvas_only() {
        let (w, h) = (20, 10);
        let mut rgb = vec![0u8; 3 * w * h];
        let mut canvas = Canvas {
            width: w,
            height: h,
            rgb: &mut rgb,
        };
        let k = Keypoint {
            x: 10.0,
            y: 5.0,
            size: 8.0,
            angle: 0.0,
            response: 0.1,
            octave: 0,
        };
        canvas.keypoints(&[k, Keypoint { x: -50.0, ..k }], [255, 0, 0]);
        let red = |x: usize, y: usize| rgb[3 * (y * w + x)] == 255;
        assert!(
            red(14, 5) && red(12, 5),
            "the radius along 0° and the circle"
        );
        assert!(red(10, 1) && red(6, 5));
        assert!(!red(0, 0));
    }
}
