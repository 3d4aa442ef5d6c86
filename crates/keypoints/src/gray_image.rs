//! A single-channel floating-point image, the input and the scale-space levels of SIFT.

/// BT.601 luma weights in 14-bit fixed point (0.299, 0.587, 0.114 × 2¹⁴), OpenCV's.
const GRAY_R: u32 = 4899;
const GRAY_G: u32 = 9617;
const GRAY_B: u32 = 1868;
const GRAY_SHIFT: u32 = 14;
const GRAY_HALF: u32 = 1 << (GRAY_SHIFT - 1);

/// The grey level of an RGB pixel.
fn luma(p: &[u8]) -> f32 {
    let [r, g, b] = [p[0], p[1], p[2]].map(u32::from);
    ((GRAY_R * r + GRAY_G * g + GRAY_B * b + GRAY_HALF) >> GRAY_SHIFT) as f32
}

/// A grey image, row-major, intensities in 0–255 as `f32` (OpenCV's `CV_32F` SIFT input).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GrayImage {
    width: usize,
    height: usize,
    data: Vec<f32>,
}

impl GrayImage {
    /// A black image of `width × height` pixels.
    pub fn new(width: usize, height: usize) -> Self {
        GrayImage {
            width,
            height,
            data: vec![0.0; width * height],
        }
    }

    /// Wraps row-major intensities; `None` when `data.len() != width · height`.
    pub fn from_vec(width: usize, height: usize, data: Vec<f32>) -> Option<Self> {
        (data.len() == width * height).then_some(GrayImage {
            width,
            height,
            data,
        })
    }

    /// Grey from 8-bit RGB (row-major, 3 bytes a pixel) with ITU-R BT.601 weights in OpenCV's
    /// 14-bit fixed point, so that the levels equal `cvtColor(…, COLOR_RGB2GRAY)`'s; `None` when
    /// the buffer's length is not `3 · width · height`.
    pub fn from_rgb8(width: usize, height: usize, rgb: &[u8]) -> Option<Self> {
        if rgb.len() != 3 * width * height {
            return None;
        }
        let data = rgb.chunks_exact(3).map(luma).collect();
        Some(GrayImage {
            width,
            height,
            data,
        })
    }

    /// Grey (as [`GrayImage::from_rgb8`]) of the region `[x0, x0 + w) × [y0, y0 + h)` of an 8-bit
    /// RGB image of `width × height` pixels, clipped to the image, each `bin × bin` block of it
    /// averaged into one pixel (`bin` ≥ 1; a partial block at the right or bottom edge is
    /// dropped). Output pixel `i` covers input pixels `x0 + bin·i … x0 + bin·i + bin − 1`, so its
    /// centre is at `x0 + bin·i + (bin − 1)/2`. `None` when the buffer's length is not
    /// `3 · width · height` or `bin` is 0. Converts only the region: a face in a video frame,
    /// brought to a working size.
    pub fn from_rgb8_region(
        width: usize,
        height: usize,
        rgb: &[u8],
        [x0, y0, w, h]: [usize; 4],
        bin: usize,
    ) -> Option<Self> {
        if rgb.len() != 3 * width * height || bin == 0 {
            return None;
        }
        let (x0, y0) = (x0.min(width), y0.min(height));
        let (w, h) = (w.min(width - x0) / bin, h.min(height - y0) / bin);
        let mut data = vec![0.0f32; w * h];
        for (oy, out) in data.chunks_exact_mut(w.max(1)).take(h).enumerate() {
            for dy in 0..bin {
                let y = y0 + oy * bin + dy;
                let row = &rgb[3 * (y * width + x0)..3 * (y * width + x0 + w * bin)];
                for (o, block) in out.iter_mut().zip(row.chunks_exact(3 * bin)) {
                    *o += block.chunks_exact(3).map(luma).sum::<f32>();
                }
            }
        }
        let scale = 1.0 / (bin * bin) as f32;
        for v in &mut data {
            *v *= scale;
        }
        Some(GrayImage {
            width: w,
            height: h,
            data,
        })
    }

    /// From 8-bit grey levels (row-major); `None` on a length mismatch.
    pub fn from_luma8(width: usize, height: usize, luma: &[u8]) -> Option<Self> {
        Self::from_vec(width, height, luma.iter().map(|&v| f32::from(v)).collect())
    }

    /// Width, pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height, pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The intensities, row-major.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// Row `y`.
    pub fn row(&self, y: usize) -> &[f32] {
        &self.data[y * self.width..(y + 1) * self.width]
    }

    /// The intensity at column `x`, row `y`.
    #[inline]
    pub fn at(&self, x: usize, y: usize) -> f32 {
        self.data[y * self.width + x]
    }

    /// Makes the image `width × height`, keeping its allocation when it is large enough; the
    /// contents are unspecified afterwards.
    pub(crate) fn resize(&mut self, width: usize, height: usize) {
        self.width = width;
        self.height = height;
        self.data.resize(width * height, 0.0);
    }

    pub(crate) fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }

    /// The sub-image `[x0, x0 + width) × [y0, y0 + height)`, clipped to the image.
    pub fn crop(&self, x0: usize, y0: usize, width: usize, height: usize) -> GrayImage {
        let x0 = x0.min(self.width);
        let y0 = y0.min(self.height);
        let width = width.min(self.width - x0);
        let height = height.min(self.height - y0);
        let mut out = GrayImage::new(width, height);
        for y in 0..height {
            out.data[y * width..(y + 1) * width].copy_from_slice(&self.row(y0 + y)[x0..x0 + width]);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_region_converts_like_the_whole_image() {
        let (w, h) = (7, 5);
        let rgb: Vec<u8> = (0..3 * w * h).map(|i| (i * 37 % 256) as u8).collect();
        let whole = GrayImage::from_rgb8(w, h, &rgb).unwrap();
        let region = GrayImage::from_rgb8_region(w, h, &rgb, [2, 1, 4, 10], 1).unwrap();
        assert_eq!((region.width(), region.height()), (4, 4));
        assert_eq!(region, whole.crop(2, 1, 4, 4));
        // 2 × 2 bins: the mean of each block's grey levels; the odd row left over is dropped.
        let binned = GrayImage::from_rgb8_region(w, h, &rgb, [1, 0, 6, 5], 2).unwrap();
        assert_eq!((binned.width(), binned.height()), (3, 2));
        let mean = (whole.at(3, 2) + whole.at(4, 2) + whole.at(3, 3) + whole.at(4, 3)) / 4.0;
        assert_eq!(binned.at(1, 1), mean);
        // OpenCV's levels: pure red 255 → 76, green → 150, blue → 29.
        let prim = GrayImage::from_rgb8(3, 1, &[255, 0, 0, 0, 255, 0, 0, 0, 255]).unwrap();
        assert_eq!(prim.data(), &[76.0, 150.0, 29.0]);
        assert!(GrayImage::from_rgb8_region(w, h, &rgb[1..], [0, 0, 1, 1], 1).is_none());
        assert!(GrayImage::from_rgb8_region(w, h, &rgb, [0, 0, 1, 1], 0).is_none());
    }
}
