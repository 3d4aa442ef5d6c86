//! Small sparse-matrix helpers over faer's compressed-column storage.

use faer::reborrow::ReborrowMut;
use faer::sparse::{SparseColMat, Triplet};
use faer::{MatMut, MatRef};

use crate::FemError;

/// A square sparse matrix with `usize` indices and `f64` values (both triangles stored).
pub type SparseMatrix = SparseColMat<usize, f64>;

/// Builds an `n × n` matrix from triplets; duplicate entries are summed.
pub fn from_triplets(
    n: usize,
    triplets: &[Triplet<usize, usize, f64>],
) -> Result<SparseMatrix, FemError> {
    SparseColMat::try_new_from_triplets(n, n, triplets).map_err(|e| FemError::Assembly {
        reason: format!("{e:?}"),
    })
}

/// `Σ cᵢ Aᵢ` for square matrices of the same size (patterns may differ).
pub fn linear_combination(terms: &[(f64, &SparseMatrix)]) -> Result<SparseMatrix, FemError> {
    let n = terms.first().map_or(0, |(_, a)| a.nrows());
    let mut triplets = Vec::with_capacity(terms.iter().map(|(_, a)| a.compute_nnz()).sum());
    for &(c, a) in terms {
        for_each_entry(a, |i, j, v| triplets.push(Triplet::new(i, j, c * v)));
    }
    from_triplets(n, &triplets)
}

/// Calls `f(row, col, value)` for every stored entry.
pub fn for_each_entry(a: &SparseMatrix, mut f: impl FnMut(usize, usize, f64)) {
    let col_ptr = a.symbolic().col_ptr();
    let row_idx = a.symbolic().row_idx();
    let val = a.val();
    for j in 0..a.ncols() {
        for p in col_ptr[j]..col_ptr[j + 1] {
            f(row_idx[p], j, val[p]);
        }
    }
}

/// `y ← α·A·x + β·y` for a symmetric `A` (so column access gives rows), `x, y` of shape n × c.
///
/// # Panics
/// If the shapes disagree or `x`, `y` are not column-major.
#[track_caller]
pub fn sym_matmul(
    a: &SparseMatrix,
    x: MatRef<'_, f64>,
    alpha: f64,
    beta: f64,
    mut y: MatMut<'_, f64>,
) {
    assert!(x.nrows() == a.ncols() && y.nrows() == a.nrows() && x.ncols() == y.ncols());
    let col_ptr = a.symbolic().col_ptr();
    let row_idx = a.symbolic().row_idx();
    let val = a.val();
    for c in 0..x.ncols() {
        let xc = x
            .col(c)
            .try_as_col_major()
            .expect("column-major x")
            .as_slice();
        let yc = y
            .rb_mut()
            .col_mut(c)
            .try_as_col_major_mut()
            .expect("column-major y")
            .as_slice_mut();
        for (i, yi) in yc.iter_mut().enumerate() {
            // A symmetric: row i of A = column i.
            let range = col_ptr[i]..col_ptr[i + 1];
            let acc: f64 = row_idx[range.clone()]
                .iter()
                .zip(&val[range])
                .map(|(&r, &v)| v * xc[r])
                .sum();
            *yi = if beta == 0.0 {
                alpha * acc
            } else {
                alpha * acc + beta * *yi
            };
        }
    }
}

/// Dense value of entry `(i, j)` (0 when not stored). For tests and diagnostics.
pub fn entry(a: &SparseMatrix, i: usize, j: usize) -> f64 {
    let col_ptr = a.symbolic().col_ptr();
    let row_idx = a.symbolic().row_idx();
    (col_ptr[j]..col_ptr[j + 1])
        .find(|&p| row_idx[p] == i)
        .map_or(0.0, |p| a.val()[p])
}
