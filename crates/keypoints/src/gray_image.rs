//! A single-channel floating-point image, the input and the scale-space levels of SIFT.

/// BT.601 luma weights in 14-bit fixed point (0.299, 0.587, 0.114 × 2¹⁴), OpenCV's.
const GRAY_R: u32 = 4899;
const GRAY_G: u32 = 9617;
const GRAY_B: u32 = 1868;
const GRAY_SHIFT: u32 = 14;
const GRAY_HALF: u32 = 1 << (GRAY_SHIFT - 1);

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
        let data = rgb
            .chunks_exact(3)
            .map(|p| {
                let [r, g, b] = [p[0], p[1], p[2]].map(u32::from);
                ((GRAY_R * r + GRAY_G * g + GRAY_B * b + GRAY_HALF) >> GRAY_SHIFT) as f32
            })
            .collect();
        Some(GrayImage {
            width,
            height,
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
