//! Cotangent Laplacian (P1 stiffness matrix), paper §4; Meyer et al. 2003; libigl `cotmatrix`.

use faer::sparse::Triplet;

use crate::sparse::{from_triplets, SparseMatrix};
use crate::triangle::{areas, dot, sub};
use crate::FemError;

/// Stiffness matrix `L_ij = ∫_Ω ∇φ_i · ∇φ_j dx` of P1 elements on a planar (`D = 2`) mesh, or
/// the Laplace–Beltrami stiffness of a triangulated surface (`D = 3`, the same cotangent
/// formula with the 3-D angles; used by the face-anchored mesh, whose domain is the canonical
/// face surface).
///
/// #V × #V, symmetric **positive** semi-definite (the sign opposite to libigl's `cotmatrix`):
/// `L_ij = −½ (cot α_ij + cot β_ij)` for an edge ij with opposite angles α, β, and the diagonal
/// is minus the sum of the row, so rows sum to 0 and constants span the null space of a
/// connected mesh. `(L f)_i = 0` at interior vertices for linear `f`; at boundary vertices
/// `L f` is the boundary flux (the natural, Neumann condition of (2.6)–(2.7)).
/// Invariant under scaling of the domain (cotangents are scale-free).
pub fn cotan_laplacian<const D: usize>(
    points: &[[f64; D]],
    triangles: &[[u32; 3]],
) -> Result<SparseMatrix, FemError> {
    let areas = areas(points, triangles)?;
    let mut triplets = Vec::with_capacity(12 * triangles.len());
    for (t, &area) in triangles.iter().zip(&areas) {
        for k in 0..3 {
            let (i, j) = (t[(k + 1) % 3] as usize, t[(k + 2) % 3] as usize);
            let (pk, pi, pj) = (points[t[k] as usize], points[i], points[j]);
            let (ei, ej) = (sub(pi, pk), sub(pj, pk));
            // cot of the angle at k = (ei · ej) / |ei × ej|, |ei × ej| = 2·area
            let half_cot = 0.5 * dot(&ei, &ej) / (2.0 * area);
            triplets.push(Triplet::new(i, j, -half_cot));
            triplets.push(Triplet::new(j, i, -half_cot));
            triplets.push(Triplet::new(i, i, half_cot));
            triplets.push(Triplet::new(j, j, half_cot));
        }
    }
    from_triplets(points.len(), &triplets)
}
