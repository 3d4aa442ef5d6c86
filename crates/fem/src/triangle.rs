//! Per-triangle geometry shared by the assemblers.

use crate::FemError;

/// Relative area below which a triangle counts as degenerate.
const DEGENERATE_AREA: f64 = 1e-14;

/// Unsigned area of every triangle of a planar mesh; errors on degenerate triangles.
pub(crate) fn areas(points: &[[f64; 2]], triangles: &[[u32; 3]]) -> Result<Vec<f64>, FemError> {
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
            let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
            if area <= DEGENERATE_AREA * scale * scale {
                Err(FemError::DegenerateTriangle { index, area })
            } else {
                Ok(area)
            }
        })
        .collect()
}
