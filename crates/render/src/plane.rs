//! Affine functions of the pixel centre: what perspective-correct interpolation evaluates per
//! pixel ([`crate::interpolation`]).

/// An affine function of the pixel centre `(x, y)`: `c + dx·(x − x₀) + dy·(y − y₀)` about the
/// origin `(x₀, y₀)` of its set-up ([`crate::interpolation::SetupPlanes::origin`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Plane {
    pub c: f64,
    pub dx: f64,
    pub dy: f64,
}

impl Plane {
    /// `Σ a_i · planes_i`.
    #[inline(always)]
    pub(crate) fn combine(planes: &[Plane; 3], a: [f64; 3]) -> Plane {
        let [p, q, r] = planes;
        Plane {
            c: a[0] * p.c + a[1] * q.c + a[2] * r.c,
            dx: a[0] * p.dx + a[1] * q.dx + a[2] * r.dx,
            dy: a[0] * p.dy + a[1] * q.dy + a[2] * r.dy,
        }
    }

    /// `Σ planes_i`: [`Plane::combine`] with unit weights (`1 · x = x` exactly).
    #[inline(always)]
    pub(crate) fn sum(planes: &[Plane; 3]) -> Plane {
        let [p, q, r] = planes;
        Plane {
            c: p.c + q.c + r.c,
            dx: p.dx + q.dx + r.dx,
            dy: p.dy + q.dy + r.dy,
        }
    }
}
