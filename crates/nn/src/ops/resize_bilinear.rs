/// The source taps of one axis of a bilinear resize (TensorFlow's `ResizeBilinear` sampling):
/// output index `o` reads input indices `lo[o]` and `hi[o]` with weights `1 − frac[o]` and
/// `frac[o]`.
#[derive(Clone, Debug, PartialEq)]
pub struct ResizeAxis {
    pub lo: Vec<usize>,
    pub hi: Vec<usize>,
    pub frac: Vec<f32>,
}

impl ResizeAxis {
    /// Taps for resizing `input` samples to `output` as TFLite's `RESIZE_BILINEAR`: scale
    /// `input / output` (`(input − 1) / (output − 1)` with `align_corners`); the source
    /// coordinate of output `o` is `(o + ½)·scale − ½` with `half_pixel_centers`, else `o·scale`;
    /// its floor and the next index are clamped to the input (so coordinates before the first or
    /// after the last sample repeat the edge, as TFLite's reference kernel).
    pub fn new(input: usize, output: usize, align_corners: bool, half_pixel_centers: bool) -> Self {
        let scale = if align_corners && output > 1 {
            (input as f32 - 1.0) / (output as f32 - 1.0)
        } else {
            input as f32 / output as f32
        };
        let last = input.saturating_sub(1) as f32;
        let mut axis = ResizeAxis {
            lo: Vec::with_capacity(output),
            hi: Vec::with_capacity(output),
            frac: Vec::with_capacity(output),
        };
        for o in 0..output {
            let v = if half_pixel_centers {
                (o as f32 + 0.5) * scale - 0.5
            } else {
                o as f32 * scale
            };
            let f = v.floor();
            let (lo, hi) = (f.clamp(0.0, last), (f + 1.0).clamp(0.0, last));
            axis.lo.push(lo as usize);
            axis.hi.push(hi as usize);
            axis.frac.push(v - f);
        }
        axis
    }
}

/// Bilinear resize of an NHWC tensor (batch 1, TFLite `RESIZE_BILINEAR`): `x` is
/// `[in_h, in_w, C]`, `y` is `[out_h, out_w, C]` with `out_h = rows.frac.len()` and
/// `out_w = cols.frac.len()`; each output is
/// `lerp(lerp(x[lo_y, lo_x], x[lo_y, hi_x], f_x), lerp(x[hi_y, lo_x], x[hi_y, hi_x], f_x), f_y)`
/// with `lerp(a, b, f) = a + (b − a)·f` (the same weights as TFLite's reference kernel).
///
/// Not inlined into the step loop (only the full-range detector uses it, on small tensors);
/// the compiler vectorises it for SSE.
///
/// # Panics
/// If a tap lies outside `x` or `y` has another size.
#[track_caller]
#[inline(never)]
pub fn resize_bilinear(
    x: &[f32],
    in_w: usize,
    c: usize,
    rows: &ResizeAxis,
    cols: &ResizeAxis,
    y: &mut [f32],
) {
    let (out_h, out_w) = (rows.frac.len(), cols.frac.len());
    assert_eq!(y.len(), out_h * out_w * c, "resize output size");
    let px = |iy: usize, ix: usize| &x[(iy * in_w + ix) * c..(iy * in_w + ix + 1) * c];
    for oy in 0..out_h {
        let (y0, y1, fy) = (rows.lo[oy], rows.hi[oy], rows.frac[oy]);
        for ox in 0..out_w {
            let (x0, x1, fx) = (cols.lo[ox], cols.hi[ox], cols.frac[ox]);
            let (tl, tr, bl, br) = (px(y0, x0), px(y0, x1), px(y1, x0), px(y1, x1));
            let out = &mut y[(oy * out_w + ox) * c..(oy * out_w + ox + 1) * c];
            for k in 0..c {
                let top = tl[k] + (tr[k] - tl[k]) * fx;
                let bottom = bl[k] + (br[k] - bl[k]) * fx;
                out[k] = top + (bottom - top) * fy;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_pixel_taps() {
        // 2 → 4, half-pixel: coordinates −0.25, 0.25, 0.75, 1.25.
        let a = ResizeAxis::new(2, 4, false, true);
        assert_eq!(a.lo, [0, 0, 0, 1]);
        assert_eq!(a.hi, [0, 1, 1, 1]);
        assert_eq!(a.frac, [0.75, 0.25, 0.75, 0.25]);
        // Without half-pixel centres: 0, 0.5, 1, 1.5.
        let b = ResizeAxis::new(2, 4, false, false);
        assert_eq!(
            (b.lo, b.hi, b.frac),
            (vec![0, 0, 1, 1], vec![1, 1, 1, 1], vec![0.0, 0.5, 0.0, 0.5])
        );
        // Align corners: 0, 1/3, 2/3, 1.
        let c = ResizeAxis::new(2, 4, true, false);
        assert_eq!(c.lo, [0, 0, 0, 1]);
        assert!((c.frac[1] - 1.0 / 3.0).abs() < 1e-7);
    }

    #[test]
    fn doubles_a_2x2_image_with_half_pixel_centres() {
        // Input [[0, 4], [8, 12]], one channel → 4×4. Each axis samples at −0.25 (the edge),
        // 0.25, 0.75 and 1.25 (the edge): from a to b, the values a, a + ¼(b−a), a + ¾(b−a), b.
        let x = [0.0, 4.0, 8.0, 12.0];
        let axis = ResizeAxis::new(2, 4, false, true);
        let mut y = [0.0; 16];
        resize_bilinear(&x, 2, 1, &axis, &axis, &mut y);
        let expected = [
            0.0, 1.0, 3.0, 4.0, //
            2.0, 3.0, 5.0, 6.0, //
            6.0, 7.0, 9.0, 10.0, //
            8.0, 9.0, 11.0, 12.0,
        ];
        assert_eq!(y, expected);
        // Two channels are resized independently.
        let x2 = [0.0, 1.0, 4.0, 1.0, 8.0, 1.0, 12.0, 1.0];
        let mut y2 = [0.0; 32];
        resize_bilinear(&x2, 2, 2, &axis, &axis, &mut y2);
        for (k, &v) in expected.iter().enumerate() {
            assert_eq!((y2[2 * k], y2[2 * k + 1]), (v, 1.0));
        }
    }
}
