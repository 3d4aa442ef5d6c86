use visage_camera::DepthMap;

/// A binary image: which pixels belong to the region to mesh. Row-major, `width × height`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mask {
    pub width: u32,
    pub height: u32,
    pub data: Vec<bool>,
}

impl Mask {
    /// A mask with every pixel set to `value`.
    pub fn filled(width: u32, height: u32, value: bool) -> Self {
        Mask {
            width,
            height,
            data: vec![value; width as usize * height as usize],
        }
    }

    /// The pixels of `depth` that hold valid depth.
    pub fn from_valid_depth(depth: &DepthMap) -> Self {
        Mask {
            width: depth.width,
            height: depth.height,
            data: depth.data.iter().map(|&d| DepthMap::is_valid(d)).collect(),
        }
    }

    /// Whether integer pixel `(u, v)` is set (`false` outside the image).
    #[inline]
    pub fn get(&self, u: i64, v: i64) -> bool {
        u >= 0
            && v >= 0
            && (u as u64) < self.width as u64
            && (v as u64) < self.height as u64
            && self.data[v as usize * self.width as usize + u as usize]
    }

    /// Number of set pixels.
    pub fn count(&self) -> usize {
        self.data.iter().filter(|&&b| b).count()
    }
}
