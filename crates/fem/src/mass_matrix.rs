//! Mass matrices of P1 finite elements (paper §4).

use faer::sparse::Triplet;

use crate::sparse::{from_triplets, SparseMatrix};
use crate::triangle::areas;
use crate::FemError;

/// Consistent mass matrix `M_ij = ∫_Ω φ_i φ_j dx` of P1 elements on a planar
/// (`D = 2`) or surface (`D = 3`) mesh.
///
/// #V × #V, symmetric positive definite; per triangle of area `A`, `A/6` on the diagonal and
/// `A/12` off it, so the entries sum to the area of Ω. `points` are domain coordinates
/// (see [`crate::domain`]); `triangles` index them.
pub fn mass_matrix<const D: usize>(
    points: &[[f64; D]],
    triangles: &[[u32; 3]],
) -> Result<SparseMatrix, FemError> {
    let areas = areas(points, triangles)?;
    let mut triplets = Vec::with_capacity(9 * triangles.len());
    for (t, &area) in triangles.iter().zip(&areas) {
        for a in 0..3 {
            for b in 0..3 {
                let v = if a == b { area / 6.0 } else { area / 12.0 };
                triplets.push(Triplet::new(t[a] as usize, t[b] as usize, v));
            }
        }
    }
    from_triplets(points.len(), &triplets)
}

/// Lumped (row-sum) mass `M_l,ii = Σ_j M_ij = ∫_Ω φ_i dx`: a third of the area of the
/// triangles around vertex i. Errors on a vertex that belongs to no triangle.
pub fn lumped_mass<const D: usize>(
    points: &[[f64; D]],
    triangles: &[[u32; 3]],
) -> Result<Vec<f64>, FemError> {
    let areas = areas(points, triangles)?;
    let mut m = vec![0.0; points.len()];
    for (t, &area) in triangles.iter().zip(&areas) {
        for &i in t {
            m[i as usize] += area / 3.0;
        }
    }
    if let Some(index) = m.iter().position(|&x| x <= 0.0) {
        return Err(FemError::IsolatedVertex { index });
    }
    Ok(m)
}
