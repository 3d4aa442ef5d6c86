//! Edge functions and the top-left fill rule, computed so that two triangles sharing an edge make
//! bit-identical, opposite decisions at every pixel centre (watertight coverage in `f64` without
//! fixed-point snapping).

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::{
    __m256d, __m512d, __mmask8, _mm256_cmp_pd, _mm256_mul_pd, _mm256_set1_pd, _mm256_sub_pd,
    _mm512_mask_cmp_pd_mask, _mm512_mul_pd, _mm512_set1_pd, _mm512_sub_pd, _CMP_GE_OQ,
};

/// An oriented triangle edge `a → b` in pixel coordinates, stored canonically.
///
/// `E(p) = sign · ((b_c − a_c) × (p − a_c))` where `(a_c, b_c)` is the edge's endpoint pair in
/// lexicographic order. A shared edge is traversed in opposite directions by its two triangles;
/// both evaluate the same canonical product (same operations, same rounding) and differ only in
/// `sign`, so `E₁(p) = −E₂(p)` exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    a: [f64; 2],
    d: [f64; 2],
    sign: f64,
    /// The least `E` counted as inside: `0` when pixel centres exactly on the edge belong to this
    /// triangle (top-left rule), else the least positive `f64` (so `E ≥ min_inside` ⟺ `E > 0`).
    min_inside: f64,
}

/// The least positive `f64` (a subnormal; the renderer never flushes subnormals to zero).
const LEAST_POSITIVE: f64 = f64::from_bits(1);

impl Edge {
    /// The edge `a → b` of a triangle whose interior is on the side where `E > 0`.
    ///
    /// Fill rule: a pixel centre with `E = 0` is inside when the edge is a *top* edge (horizontal,
    /// running in +u) or a *left* edge (running in −v, image rows pointing down). This is the same
    /// as testing the sample point displaced by `(+ε, +ε²)`, a consistent infinitesimal
    /// perturbation, so each centre of a closed fan is covered exactly once, vertices included.
    pub fn new(a: [f64; 2], b: [f64; 2]) -> Edge {
        let d = [b[0] - a[0], b[1] - a[1]];
        let owns_ties = d[1] < 0.0 || (d[1] == 0.0 && d[0] > 0.0);
        let (ac, bc, sign) = if (a[0], a[1]) <= (b[0], b[1]) {
            (a, b, 1.0)
        } else {
            (b, a, -1.0)
        };
        Edge {
            a: ac,
            d: [bc[0] - ac[0], bc[1] - ac[1]],
            sign,
            min_inside: if owns_ties { 0.0 } else { LEAST_POSITIVE },
        }
    }

    /// The row-constant part of `E` at pixel row `y`.
    #[inline(always)]
    pub fn row(&self, y: f64) -> f64 {
        self.d[0] * (y - self.a[1])
    }

    /// `E(x, y)` given `row = self.row(y)`.
    #[inline(always)]
    pub fn eval(&self, row: f64, x: f64) -> f64 {
        self.sign * (row - self.d[1] * (x - self.a[0]))
    }

    /// `E` as an affine function about pixel centre `(x, y)`: `(E(x, y), ∂E/∂x, ∂E/∂y)`, the
    /// value by [`Edge::eval`] (so exactly the scan's at that centre).
    #[inline]
    pub fn plane_at(&self, x: f64, y: f64) -> [f64; 3] {
        [
            self.eval(self.row(y), x),
            -self.sign * self.d[1],
            self.sign * self.d[0],
        ]
    }

    /// Whether a value `e = E(p)` puts `p` inside this edge's half-plane under the fill rule.
    #[inline(always)]
    pub fn inside(&self, e: f64) -> bool {
        // `e > 0 ∨ (e = 0 ∧ owns ties)` in one comparison (false for NaN, true for −0 when the
        // edge owns ties).
        e >= self.min_inside
    }

    /// Whether pixel centres exactly on the edge belong to this triangle (top-left rule).
    #[cfg(test)]
    fn owns_ties(&self) -> bool {
        self.min_inside == 0.0
    }
}

/// Four-lane twins of [`Edge::eval`] and [`Edge::inside`] for four pixel centres of one row
/// (AVX): lane by lane the same operations in the same order, so the same bits.
#[cfg(target_arch = "x86_64")]
impl Edge {
    /// `E` at the centres `x` of one row, `row = self.row(y)` in every lane.
    #[inline]
    #[target_feature(enable = "avx")]
    pub(crate) fn eval_x4(&self, row: __m256d, x: __m256d) -> __m256d {
        let t = _mm256_sub_pd(x, _mm256_set1_pd(self.a[0]));
        let v = _mm256_sub_pd(row, _mm256_mul_pd(_mm256_set1_pd(self.d[1]), t));
        _mm256_mul_pd(_mm256_set1_pd(self.sign), v)
    }

    /// All bits set in the lanes whose value `e = E(p)` puts `p` inside (`e ≥ min_inside`, an
    /// ordered comparison: false for NaN).
    #[inline]
    #[target_feature(enable = "avx")]
    pub(crate) fn inside_x4(&self, e: __m256d) -> __m256d {
        _mm256_cmp_pd::<_CMP_GE_OQ>(e, _mm256_set1_pd(self.min_inside))
    }
}

/// Eight-lane twins of [`Edge::row`], [`Edge::eval`] and [`Edge::inside`] for eight rows or
/// eight pixel centres of one row (AVX-512), with the evaluation split into its row and column
/// parts so that a scan computes each once per row and per column: lane by lane the same
/// operations in the same order, so the same bits.
#[cfg(target_arch = "x86_64")]
impl Edge {
    /// [`Edge::row`] at the rows `y`.
    #[inline]
    #[target_feature(enable = "avx512f")]
    pub(crate) fn row_x8(&self, y: __m512d) -> __m512d {
        _mm512_mul_pd(
            _mm512_set1_pd(self.d[0]),
            _mm512_sub_pd(y, _mm512_set1_pd(self.a[1])),
        )
    }

    /// The part of `E` that depends on the column only, `d_y · (x − a_x)`, at the centres `x`.
    #[inline]
    #[target_feature(enable = "avx512f")]
    pub(crate) fn column_x8(&self, x: __m512d) -> __m512d {
        let t = _mm512_sub_pd(x, _mm512_set1_pd(self.a[0]));
        _mm512_mul_pd(_mm512_set1_pd(self.d[1]), t)
    }

    /// `E` at the centres of one row given `row = self.row(y)` in every lane and
    /// `column = self.column_x8(x)`.
    #[inline]
    #[target_feature(enable = "avx512f")]
    pub(crate) fn eval_x8(&self, row: __m512d, column: __m512d) -> __m512d {
        _mm512_mul_pd(_mm512_set1_pd(self.sign), _mm512_sub_pd(row, column))
    }

    /// The lanes of `lanes` whose value `e = E(p)` puts `p` inside (`e ≥ min_inside`, an
    /// ordered comparison: false for NaN).
    #[inline]
    #[target_feature(enable = "avx512f")]
    pub(crate) fn inside_x8(&self, lanes: __mmask8, e: __m512d) -> __mmask8 {
        _mm512_mask_cmp_pd_mask::<_CMP_GE_OQ>(lanes, e, _mm512_set1_pd(self.min_inside))
    }
}

/// Twice the signed area of triangle `p` in pixel coordinates: `(p₁ − p₀) × (p₂ − p₀)`. Positive
/// for triangles that run clockwise on screen (rows pointing down), i.e. back-facing ones for a
/// right-handed mesh with outward normals.
#[inline]
pub fn signed_area2(p: &[[f64; 2]; 3]) -> f64 {
    (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_edge_values_are_exact_negatives() {
        let (a, b) = ([0.1234567, 7.654321], [13.37, -2.25]);
        let (e1, e2) = (Edge::new(a, b), Edge::new(b, a));
        for &(x, y) in &[(3.0, 4.0), (0.0, 0.0), (100.0, -50.0), (6.0, 2.0)] {
            assert_eq!(e1.eval(e1.row(y), x), -e2.eval(e2.row(y), x));
        }
        assert_ne!(
            e1.owns_ties(),
            e2.owns_ties(),
            "exactly one side owns centres on the edge"
        );
        let [v, dx, dy] = e1.plane_at(3.0, 4.0);
        let (du, dv) = (5.0, -2.0);
        let direct = e1.eval(e1.row(4.0 + dv), 3.0 + du);
        assert!((v + dx * du + dy * dv - direct).abs() <= 1e-12 * direct.abs());
        let (h1, h2) = (
            Edge::new([0.0, 1.0], [5.0, 1.0]),
            Edge::new([5.0, 1.0], [0.0, 1.0]),
        );
        assert_ne!(h1.owns_ties(), h2.owns_ties(), "also for horizontal edges");
        // The one-comparison test agrees with its definition at the edge cases.
        for e in [h1, h2, e1, e2] {
            for v in [
                0.0,
                -0.0,
                LEAST_POSITIVE,
                -LEAST_POSITIVE,
                1.0,
                -1.0,
                f64::NAN,
            ] {
                assert_eq!(e.inside(v), v > 0.0 || (v == 0.0 && e.owns_ties()), "{v}");
            }
        }
    }
}
