/// A face detection (BlazeFace), in the coordinates stated by the producer.
///
/// Keypoints, in MediaPipe's order: 0 right eye, 1 left eye, 2 nose tip, 3 mouth centre,
/// 4 right ear tragion, 5 left ear tragion ("right" = the subject's right, on the image's left).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Detection {
    /// Face score `sigmoid(logit)` ∈ [0, 1].
    pub score: f32,
    /// Box centre `(x, y)`.
    pub center: [f32; 2],
    /// Box size `(w, h)`.
    pub size: [f32; 2],
    /// The six keypoints `(x, y)`.
    pub keypoints: [[f32; 2]; 6],
}

impl Detection {
    /// Box as `[x_min, y_min, w, h]`.
    pub fn bbox(&self) -> [f32; 4] {
        [
            self.center[0] - 0.5 * self.size[0],
            self.center[1] - 0.5 * self.size[1],
            self.size[0],
            self.size[1],
        ]
    }

    /// Intersection over union of the two boxes (0 when either is empty).
    pub fn iou(&self, other: &Detection) -> f32 {
        let [ax, ay, aw, ah] = self.bbox();
        let [bx, by, bw, bh] = other.bbox();
        let iw = ((ax + aw).min(bx + bw) - ax.max(bx)).max(0.0);
        let ih = ((ay + ah).min(by + bh) - ay.max(by)).max(0.0);
        let inter = iw * ih;
        let union = aw * ah + bw * bh - inter;
        if union > 0.0 {
            inter / union
        } else {
            0.0
        }
    }

    /// Maps every coordinate by `p ↦ p · scale + offset` (per axis).
    pub fn map(&self, scale: [f32; 2], offset: [f32; 2]) -> Detection {
        let m = |p: [f32; 2]| [p[0] * scale[0] + offset[0], p[1] * scale[1] + offset[1]];
        Detection {
            score: self.score,
            center: m(self.center),
            size: [self.size[0] * scale[0], self.size[1] * scale[1]],
            keypoints: self.keypoints.map(m),
        }
    }
}
