//! Biharmonic stiffness of the smoothness term (paper Eq. (2.4); ERRATA 3).

use faer::sparse::Triplet;

use crate::sparse::{from_triplets, SparseMatrix};
use crate::FemError;

/// `K = Lᵀ M_l⁻¹ L`: the mixed P1 discretisation of `∫_Ω |ΔS|² dx` with free (Neumann)
/// boundary behaviour, from the stiffness matrix `L` (see [`crate::cotan_laplacian`]) and the
/// lumped mass `m_lumped` (#V).
///
/// #V × #V, symmetric positive semi-definite; on a connected mesh its null space is exactly the
/// constants (linear functions are *not* in it: `L f ≠ 0` at boundary vertices). Under a
/// scaling of the domain by `s`, `L` is unchanged and `M_l` scales by `s²`, so `K` scales by
/// `s⁻²` — which is why λ is quoted in reference pixels ([`crate::domain`]).
pub fn biharmonic(l: &SparseMatrix, m_lumped: &[f64]) -> Result<SparseMatrix, FemError> {
    let n = l.nrows();
    if m_lumped.len() != n {
        return Err(FemError::Dimension {
            what: "lumped mass length",
            expected: n,
            got: m_lumped.len(),
        });
    }
    let col_ptr = l.symbolic().col_ptr();
    let row_idx = l.symbolic().row_idx();
    let val = l.val();
    let mut acc = vec![0.0; n];
    let mut touched: Vec<usize> = Vec::new();
    let mut mark = vec![false; n];
    let mut triplets = Vec::new();
    // Column j of K = Σ_k L[:, k] · (L_kj / m_k), with L symmetric.
    for j in 0..n {
        for p in col_ptr[j]..col_ptr[j + 1] {
            let k = row_idx[p];
            let w = val[p] / m_lumped[k];
            for q in col_ptr[k]..col_ptr[k + 1] {
                let i = row_idx[q];
                if !mark[i] {
                    mark[i] = true;
                    touched.push(i);
                }
                acc[i] += val[q] * w;
            }
        }
        for &i in &touched {
            triplets.push(Triplet::new(i, j, acc[i]));
            acc[i] = 0.0;
            mark[i] = false;
        }
        touched.clear();
    }
    from_triplets(n, &triplets)
}
