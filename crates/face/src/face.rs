use crate::{Detection, Eyes, FrameLandmarks};

/// One face found in a frame: detector output (if the detector ran for it) and landmarks.
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// Detection score ∈ [0, 1]; for a tracked face (no detector run) the presence score.
    pub score: f32,
    /// Face box `[x, y, w, h]` in frame pixels (visage convention): the detector's box, or the
    /// landmarks' bounding box when tracked.
    pub bbox: [f32; 4],
    /// The detection (frame pixels, MediaPipe convention) when the detector produced this face.
    pub detection: Option<Detection>,
    /// Landmarks in frame pixels.
    pub landmarks: FrameLandmarks,
    /// Eye contours and irises in frame pixels (`right` = the subject's right eye, on the
    /// image's left): the attention face mesh's, or the iris network's when it is loaded
    /// ([`crate::FaceMesh::iris`]); `None` without either.
    pub eyes: Option<Eyes>,
}

/// Axis-aligned bounding box `[x, y, w, h]` of the points' `(x, y)`.
pub fn points_bbox(points: &[[f32; 3]]) -> [f32; 4] {
    let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    for p in points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    [lo[0], lo[1], hi[0] - lo[0], hi[1] - lo[1]]
}
