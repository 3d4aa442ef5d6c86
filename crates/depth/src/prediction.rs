//! A network's output over the part of the frame it saw: the region, the raw values, and the
//! frame-pixel ↔ output-pixel mapping (half-pixel centres, as image resizing does).

use visage_camera::{DepthKind, DepthMap};

/// A rectangle of the frame, pixels, by its edges: pixel `(i, j)`'s centre is at `(i, j)`, so
/// the whole of a `W × H` frame is `left = top = −0.5`, `width = W`, `height = H`. It may reach
/// beyond the frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameRegion {
    pub left: f64,
    pub top: f64,
    pub width: f64,
    pub height: f64,
}

impl FrameRegion {
    /// The whole of a `width × height` frame.
    pub fn frame(width: u32, height: u32) -> FrameRegion {
        FrameRegion {
            left: -0.5,
            top: -0.5,
            width: width as f64,
            height: height as f64,
        }
    }

    /// A face box `[x, y, w, h]` (pixels) grown by `margin` × its larger side on each side, at
    /// aspect ratio `aspect` (width / height), centred on the box.
    pub fn around_face(face_box: [f32; 4], margin: f64, aspect: f64) -> FrameRegion {
        let [x, y, w, h] = face_box.map(f64::from);
        let side = w.max(h) * (1.0 + 2.0 * margin);
        let (width, height) = if aspect >= 1.0 {
            (side * aspect, side)
        } else {
            (side, side / aspect)
        };
        FrameRegion {
            left: x + 0.5 * w - 0.5 * width,
            top: y + 0.5 * h - 0.5 * height,
            width,
            height,
        }
    }

    /// The whole frame grown on one axis to aspect ratio `aspect` (letterbox), centred.
    pub fn padded_frame(width: u32, height: u32, aspect: f64) -> FrameRegion {
        let f = FrameRegion::frame(width, height);
        if f.width / f.height >= aspect {
            let h = f.width / aspect;
            FrameRegion {
                top: f.top - 0.5 * (h - f.height),
                height: h,
                ..f
            }
        } else {
            let w = f.height * aspect;
            FrameRegion {
                left: f.left - 0.5 * (w - f.width),
                width: w,
                ..f
            }
        }
    }

    /// The frame position of the centre of pixel `(a, b)` of a `columns × rows` grid laid over
    /// the region.
    #[inline]
    pub fn grid_to_frame(&self, columns: u32, rows: u32, a: f64, b: f64) -> [f64; 2] {
        [
            self.left + (a + 0.5) * self.width / columns as f64,
            self.top + (b + 0.5) * self.height / rows as f64,
        ]
    }

    /// The grid position (pixel-centre coordinates) of frame position `(u, v)`.
    #[inline]
    pub fn frame_to_grid(&self, columns: u32, rows: u32, u: f64, v: f64) -> [f64; 2] {
        [
            (u - self.left) * columns as f64 / self.width - 0.5,
            (v - self.top) * rows as f64 / self.height - 0.5,
        ]
    }
}

/// A network's raw output (one value per output pixel, in its own units) over a region.
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    pub region: FrameRegion,
    pub width: u32,
    pub height: u32,
    /// Row-major, `width × height`.
    pub values: Vec<f32>,
}

impl Prediction {
    /// The output bilinearly interpolated at frame position `(u, v)` (values that are not
    /// finite left out); `None` outside the region (within half an output pixel of its edge
    /// the edge value holds).
    pub fn at(&self, u: f64, v: f64) -> Option<f32> {
        let r = &self.region;
        if !(u >= r.left && v >= r.top && u <= r.left + r.width && v <= r.top + r.height) {
            return None;
        }
        let [x, y] = r.frame_to_grid(self.width, self.height, u, v);
        Some(bilinear(&self.values, self.width, self.height, x, y))
    }

    /// A `width × height` depth map of the frame: `to_depth(value)` (metres, `kind`) at every
    /// pixel the region covers, 0 elsewhere and where it gives no positive finite depth or one
    /// beyond `max_depth`. The output is converted first and the depth interpolated (a plane
    /// stays a plane to within the interpolation).
    pub fn depth_map(
        &self,
        width: u32,
        height: u32,
        kind: DepthKind,
        max_depth: f64,
        to_depth: impl Fn(f64) -> f64,
    ) -> DepthMap {
        let converted: Vec<f32> = self
            .values
            .iter()
            .map(|&x| {
                let z = to_depth(x as f64);
                if z.is_finite() && z > 0.0 && z <= max_depth {
                    z as f32
                } else {
                    f32::NAN
                }
            })
            .collect();
        let mut map = DepthMap::empty(width, height, kind);
        let r = &self.region;
        let clamp = |lo: f64, n: u32| lo.ceil().clamp(0.0, n as f64) as u32;
        let (u0, u1) = (clamp(r.left, width), clamp(r.left + r.width, width));
        let (v0, v1) = (clamp(r.top, height), clamp(r.top + r.height, height));
        // Per column: the grid column and weight, computed once.
        let (gw, gh) = (self.width as usize, self.height as usize);
        let axis = |g: f64, n: usize| {
            let g = g.clamp(0.0, (n - 1) as f64);
            let i = g.floor() as usize;
            (i, (i + 1).min(n - 1), (g - i as f64) as f32)
        };
        let columns: Vec<(usize, usize, f32)> = (u0..u1)
            .map(|u| {
                axis(
                    r.frame_to_grid(self.width, self.height, u as f64, 0.0)[0],
                    gw,
                )
            })
            .collect();
        for v in v0..v1 {
            let (j0, j1, fy) = axis(
                r.frame_to_grid(self.width, self.height, 0.0, v as f64)[1],
                gh,
            );
            let (top, bottom) = (&converted[j0 * gw..][..gw], &converted[j1 * gw..][..gw]);
            let row = &mut map.data[v as usize * width as usize..][..width as usize];
            for (out, &(i0, i1, fx)) in row[u0 as usize..u1 as usize].iter_mut().zip(&columns) {
                let z = blend(top[i0], top[i1], bottom[i0], bottom[i1], fx, fy);
                if z.is_finite() {
                    *out = z;
                }
            }
        }
        map
    }
}

/// Bilinear blend of four corner values with weights from `fx`, `fy`; corners that are not
/// finite are left out and the others renormalised (NaN when none remains).
#[inline]
fn blend(a: f32, b: f32, c: f32, d: f32, fx: f32, fy: f32) -> f32 {
    if a.is_finite() && b.is_finite() && c.is_finite() && d.is_finite() {
        let top = a + fx * (b - a);
        let bottom = c + fx * (d - c);
        return top + fy * (bottom - top);
    }
    let mut sum = 0.0f32;
    let mut weight = 0.0f32;
    for (v, w) in [
        (a, (1.0 - fx) * (1.0 - fy)),
        (b, fx * (1.0 - fy)),
        (c, (1.0 - fx) * fy),
        (d, fx * fy),
    ] {
        if w > 0.0 && v.is_finite() {
            sum += w * v;
            weight += w;
        }
    }
    if weight > 0.0 {
        sum / weight
    } else {
        f32::NAN
    }
}

/// Bilinear interpolation of a row-major grid at pixel-centre position `(x, y)`, clamped to
/// the grid's edge; values that are not finite (no data) are left out and the weights of the
/// others renormalised (NaN when none remains).
#[inline]
pub(crate) fn bilinear(values: &[f32], width: u32, height: u32, x: f64, y: f64) -> f32 {
    let (w, h) = (width as usize, height as usize);
    let x = x.clamp(0.0, (w - 1) as f64);
    let y = y.clamp(0.0, (h - 1) as f64);
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
    let at = |i: usize, j: usize| values[j * w + i];
    blend(at(x0, y0), at(x1, y0), at(x0, y1), at(x1, y1), fx, fy)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_and_frame_positions_invert_each_other() {
        let r = FrameRegion::around_face([100.0, 50.0, 80.0, 100.0], 0.5, 1.0);
        assert!((r.width - 200.0).abs() < 1e-12 && (r.height - 200.0).abs() < 1e-12);
        assert!((r.left - 40.0).abs() < 1e-12 && (r.top + 0.0).abs() < 1e-12);
        let [u, v] = r.grid_to_frame(64, 64, 10.0, 20.0);
        let [a, b] = r.frame_to_grid(64, 64, u, v);
        assert!((a - 10.0).abs() < 1e-12 && (b - 20.0).abs() < 1e-12);
        // A full-frame grid of the frame's size is the identity.
        let f = FrameRegion::frame(320, 240);
        assert_eq!(f.grid_to_frame(320, 240, 7.0, 9.0), [7.0, 9.0]);
        let p = FrameRegion::padded_frame(320, 240, 1.0);
        assert_eq!((p.width, p.height, p.top), (320.0, 320.0, -40.5));
    }

    #[test]
    fn a_linear_output_is_reproduced_at_every_covered_pixel() {
        // 8 × 4 output over frame pixels 0..16 × 0..8: value = u + 10 v at its centres.
        let region = FrameRegion::frame(16, 8);
        let (w, h) = (8, 4);
        let values = (0..h)
            .flat_map(|b| {
                (0..w).map(move |a| {
                    let [u, v] = region.grid_to_frame(w, h, a as f64, b as f64);
                    (u + 10.0 * v) as f32
                })
            })
            .collect();
        let p = Prediction {
            region,
            width: w,
            height: h,
            values,
        };
        assert!((p.at(5.0, 3.0).unwrap() - 35.0).abs() < 1e-5);
        assert!(p.at(-1.0, 3.0).is_none());
        let map = p.depth_map(16, 8, DepthKind::Z, 100.0, |x| x);
        // Inside the outer half output pixel the values are exact.
        assert!((map.at(6, 4) - 46.0).abs() < 1e-4);
        assert!((map.at(0, 0) - 5.5).abs() < 1e-4, "the edge value holds");
        let none = p.depth_map(16, 8, DepthKind::Z, 100.0, |x| x - 20.0);
        assert_eq!(none.at(0, 0), 0.0, "no positive depth: none");
    }
}
