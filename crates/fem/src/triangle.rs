//! Per-triangle geometry shared by the assemblers.

use crate::FemError;

/// Relative area below which a triangle counts as degenerate.
const DEGENERATE_AREA: f64 = 1e-14;

/// Unsigned area of every triangle of a planar (`D = 2`) or surface (`D = 3`) mesh; errors on
/// degenerate triangles.
pub(crate) fn areas<const D: usize>(
    points: &[[f64; D]],
    triangles: &[[u32; 3]],
) -> Result<Vec<f64>, FemError> {
    let scale = points
        .iter()
        .flat_map(|p| p.iter())
        .fold(0.0f64, |m, c| m.max(c.abs()))
        .max(f64::MIN_POSITIVE);
    triangles
        .iter()
        .enumerate()
        .map(|(index, t)| {
            let [a, b, c] = t.map(|i| points[i as usize]);
            let area = 0.5 * cross_norm(&sub(b, a), &sub(c, a));
            if area <= DEGENERATE_AREA * scale * scale {
                Err(FemError::DegenerateTriangle { index, area })
            } else {
                Ok(area)
            }
        })
        .collect()
}

/// `b − a`.
pub(crate) fn sub<const D: usize>(b: [f64; D], a: [f64; D]) -> [f64; D] {
    std::array::from_fn(|i| b[i] - a[i])
}

/// `a · b`.
pub(crate) fn dot<const D: usize>(a: &[f64; D], b: &[f64; D]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `|a × b|` in any dimension: the area of the parallelogram spanned by `a` and `b`
/// (`|a|²|b|² − (a·b)²` by Lagrange's identity, evaluated as a sum of 2 × 2 minors so that it
/// stays accurate for slivers).
pub(crate) fn cross_norm<const D: usize>(a: &[f64; D], b: &[f64; D]) -> f64 {
    let mut sum = 0.0;
    for i in 0..D {
        for j in i + 1..D {
            let m = a[i] * b[j] - a[j] * b[i];
            sum += m * m;
        }
    }
    sum.sqrt()
}
