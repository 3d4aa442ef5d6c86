//! Geometric nested dissection: a fill-reducing elimination order for matrices whose unknowns
//! sit at known points of the plane (George 1973; the geometric variant of METIS-style
//! orderings). An alternative to AMD for [`crate::Factorization`].

use crate::sparse::SparseMatrix;

/// Sub-domains at most this large are not split further.
const LEAF_SIZE: usize = 48;

/// Elimination order (`order[k]` = the unknown eliminated k-th) of the symmetric matrix `a`
/// whose unknown `i` sits at `points[i]`: split the point set at the median of its longer
/// extent, take as separator the vertices of the lower half that are coupled (a nonzero of `a`)
/// to the upper half, order both halves recursively, and the separator last.
///
/// # Panics
/// If `points` and `a` disagree in size.
#[track_caller]
pub fn nested_dissection(points: &[[f64; 2]], a: &SparseMatrix) -> Vec<usize> {
    let n = points.len();
    assert!(a.nrows() == n && a.ncols() == n);
    let mut side = vec![0u8; n];
    let mut order = Vec::with_capacity(n);
    let ids: Vec<usize> = (0..n).collect();
    dissect(points, a, ids, &mut side, &mut order);
    order
}

fn dissect(
    points: &[[f64; 2]],
    a: &SparseMatrix,
    mut ids: Vec<usize>,
    side: &mut [u8],
    order: &mut Vec<usize>,
) {
    if ids.len() <= LEAF_SIZE {
        order.extend_from_slice(&ids);
        return;
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for &i in &ids {
        for c in 0..2 {
            lo[c] = lo[c].min(points[i][c]);
            hi[c] = hi[c].max(points[i][c]);
        }
    }
    let axis = usize::from(hi[1] - lo[1] > hi[0] - lo[0]);
    let mid = ids.len() / 2;
    ids.select_nth_unstable_by(mid, |&p, &q| points[p][axis].total_cmp(&points[q][axis]));
    let (lower, upper) = ids.split_at(mid);
    for &i in upper {
        side[i] = 2;
    }
    let col_ptr = a.symbolic().col_ptr();
    let row_idx = a.symbolic().row_idx();
    let (mut left, mut separator) = (Vec::with_capacity(lower.len()), Vec::new());
    for &i in lower {
        let coupled = row_idx[col_ptr[i]..col_ptr[i + 1]]
            .iter()
            .any(|&j| side[j] == 2);
        if coupled {
            separator.push(i);
        } else {
            left.push(i);
        }
    }
    let right = upper.to_vec();
    for &i in &right {
        side[i] = 0;
    }
    dissect(points, a, left, side, order);
    dissect(points, a, right, side, order);
    order.extend_from_slice(&separator);
}
