//! sRGB (IEC 61966-2-1) ↔ linear RGB, per channel: mesh files (PLY, OBJ) and 8-bit images store
//! display (sRGB-encoded) colours; [`crate::TriMesh`] and the renderer work in linear RGB.
//! Values are `f32` channel intensities in `[0, 1]`, or bytes `0..=255` for the `_u8` forms.

/// sRGB-encoded value in `[0, 1]` → linear.
#[inline]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear value → sRGB-encoded, clamped to `[0, 1]` (NaN → 0).
#[inline]
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// An 8-bit sRGB value → linear.
#[inline]
pub fn srgb_to_linear_u8(c: u8) -> f32 {
    srgb_to_linear(c as f32 / 255.0)
}

/// A linear value → 8-bit sRGB, rounded (clamped to `[0, 1]` first, NaN → 0).
#[inline]
pub fn linear_to_srgb_u8(c: f32) -> u8 {
    (linear_to_srgb(c) * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_every_byte() {
        for b in 0..=255u8 {
            assert_eq!(linear_to_srgb_u8(srgb_to_linear_u8(b)), b);
        }
        assert_eq!(linear_to_srgb_u8(f32::NAN), 0);
        assert_eq!(linear_to_srgb_u8(7.0), 255);
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
    }
}
