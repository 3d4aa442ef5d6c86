//! Projective texturing: texture coordinates from where each vertex projects in a camera frame,
//! so a reconstruction is coloured from its own video frame.

use visage_camera::Intrinsics;

use crate::mat4::Mat4;

/// UVs (OBJ/OpenGL convention of [`crate::texture::Texture`]: `v` up) of the points `positions`
/// (#V × 3, world coordinates) in the image of a camera with intrinsics `k` and world → camera
/// transform `view` (the identity when the positions are camera coordinates, as `visage fuse`
/// writes them).
///
/// Pixel position `(x, y)` (centre of pixel `(i, j)` at `(i, j)`) maps to
/// `u = (x + ½)/W`, `v = 1 − (y + ½)/H`, so a bilinear sample at that UV reads the frame exactly
/// at `(x, y)`. Points with camera `z ≤ 0` (behind the camera) get NaN coordinates, which the
/// sampler turns into transparent black.
pub fn projective_uvs(positions: &[[f64; 3]], k: &Intrinsics, view: &Mat4) -> Vec<[f64; 2]> {
    let (w, h) = (k.width as f64, k.height as f64);
    positions
        .iter()
        .map(|&p| {
            let c = view.transform_point(p);
            if c[2] > 0.0 {
                let [x, y] = k.project(c);
                [(x + 0.5) / w, 1.0 - (y + 0.5) / h]
            } else {
                [f64::NAN; 2]
            }
        })
        .collect()
}
