//! Colour encoding in mesh files: PLY and OBJ store display (sRGB-encoded) colours, `TriMesh`
//! keeps linear RGB.

/// sRGB-encoded `[0, 1]` → linear (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear → sRGB-encoded, clamped to `[0, 1]`.
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear → 8-bit sRGB, rounded.
pub fn linear_to_srgb_u8(c: f32) -> u8 {
    (linear_to_srgb(c) * 255.0 + 0.5) as u8
}
