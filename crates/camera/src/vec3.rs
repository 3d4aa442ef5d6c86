//! The small 3-vector operations on `[f64; 3]` every crate needs (points and directions in
//! metres, camera or model coordinates).
//!
//! Each function spells out its floating-point operations in a fixed order — products and
//! sums left to right, no fused multiply-add — so that callers get the same bits they got from
//! the hand-written copies these replace: `dot(a, b)` is `(a₀b₀ + a₁b₁) + a₂b₂`, `norm(a)` is
//! `√dot(a, a)`. Code that needs another order (a compensated sum, a generic dimension) keeps
//! its own function.

/// `a · b`, summed as `(a₀b₀ + a₁b₁) + a₂b₂`.
#[inline]
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `a × b` (right-handed).
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a + b`.
#[inline]
pub fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a − b`.
#[inline]
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `s a`.
#[inline]
pub fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// `‖a‖ = √(a · a)`.
#[inline]
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// `‖a − b‖²`.
#[inline]
pub fn distance2(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}

/// `‖a − b‖`.
#[inline]
pub fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm(sub(a, b))
}

/// `a / ‖a‖` (each component divided by the norm, not multiplied by its reciprocal), or `a`
/// unchanged when `‖a‖ = 0` (or is NaN).
#[inline]
pub fn normalize(a: [f64; 3]) -> [f64; 3] {
    let n = norm(a);
    if n > 0.0 {
        [a[0] / n, a[1] / n, a[2] / n]
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Vectors whose products and sums round, so that a different order would show.
    const SAMPLES: [[f64; 3]; 5] = [
        [0.1, 0.2, 0.3],
        [1e17, 1.0, -1e17],
        [-0.7, 3.3e-9, 12.25],
        [0.0, -0.0, 0.0],
        [1.0 / 3.0, -2.0 / 7.0, 5.0 / 11.0],
    ];

    #[test]
    fn dot_sums_left_to_right() {
        for a in SAMPLES {
            for b in SAMPLES {
                let expected = (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
                assert_eq!(dot(a, b).to_bits(), expected.to_bits(), "{a:?} · {b:?}");
            }
        }
        // (1e17 + 1) − 1e17 = 0 in this order; (1e17 − 1e17) + 1 would give 1.
        assert_eq!(dot([1e17, 1.0, -1e17], [1.0; 3]), 0.0);
    }

    #[test]
    fn cross_is_perpendicular_and_right_handed() {
        assert_eq!(cross([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
        let (a, b) = (SAMPLES[0], SAMPLES[4]);
        let c = cross(a, b);
        assert!(dot(c, a).abs() < 1e-15 && dot(c, b).abs() < 1e-15);
    }

    #[test]
    fn distances_and_norms_agree() {
        for a in SAMPLES {
            for b in SAMPLES {
                let d = sub(a, b);
                assert_eq!(distance2(a, b).to_bits(), dot(d, d).to_bits());
                assert_eq!(distance(a, b).to_bits(), norm(d).to_bits());
                assert_eq!(add(d, b), add(b, d));
            }
        }
        assert_eq!(scale([1.0, -2.0, 0.5], 2.0), [2.0, -4.0, 1.0]);
    }

    #[test]
    fn normalize_gives_unit_vectors_and_leaves_zero_alone() {
        let u = normalize([3.0, 0.0, -4.0]);
        assert_eq!(u, [0.6, 0.0, -0.8]);
        assert!((norm(normalize(SAMPLES[2])) - 1.0).abs() < 1e-15);
        assert_eq!(normalize([0.0; 3]), [0.0; 3]);
    }
}
