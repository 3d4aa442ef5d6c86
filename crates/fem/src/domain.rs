//! Coordinates of the image-plane domain Ω that make λ independent of resolution and units.
//!
//! The combined energy (the paper's unnumbered functional after Eq. 2.5) has three terms. The
//! data and temporal terms are ∫|S − ·|² dx and the smoothness term is λ∫|ΔS|² dx, so λ
//! carries the units (domain length)⁴: with Ω measured in pixels, the same λ would smooth
//! twice as much (in angle) on an image of half the resolution. We measure Ω in **reference
//! pixels**: `ξ = F_REF · ((u − c_x)/f_x, (v − c_y)/f_y)`, the
//! normalised image coordinates scaled by [`REFERENCE_FOCAL_PX`]. A given λ then smooths over
//! the same visual angle at every resolution, and on a VGA camera with `f = 525 px` (Kinect,
//! TUM RGB-D) ξ is the pixel, so the paper's λ = 2.5 "in pixels" (ERRATA 6) keeps its meaning.
//! The smoothing length is `λ^{1/4}` reference pixels (≈ 1.26 for λ = 2.5).
//!
//! Depth units do not matter: every term is quadratic in S, so scaling metres to millimetres
//! scales the energy and leaves the minimiser unchanged. μ is dimensionless.

use visage_camera::Intrinsics;

/// The focal length (pixels) that defines one reference pixel of the domain Ω.
pub const REFERENCE_FOCAL_PX: f64 = 525.0;

/// Domain coordinates ξ (reference pixels) of image positions `(u, v)` (pixels).
pub fn domain_coordinates(points_px: &[[f64; 2]], k: &Intrinsics) -> Vec<[f64; 2]> {
    points_px
        .iter()
        .map(|p| {
            [
                REFERENCE_FOCAL_PX * (p[0] - k.cx) / k.fx,
                REFERENCE_FOCAL_PX * (p[1] - k.cy) / k.fy,
            ]
        })
        .collect()
}

/// Area of one image pixel in the domain's units (reference pixels²).
pub fn pixel_area(k: &Intrinsics) -> f64 {
    (REFERENCE_FOCAL_PX / k.fx) * (REFERENCE_FOCAL_PX / k.fy)
}
