//! Sparse Cholesky factorisation, computed once and reused for every frame (paper §4).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use faer::perm::PermRef;
use faer::{Conj, MatMut, Par, Side};

use crate::sparse::SparseMatrix;
use crate::FemError;

/// Numeric factorisations computed by this process (see [`Factorization::numeric_count`]).
static NUMERIC_FACTORIZATIONS: AtomicUsize = AtomicUsize::new(0);

/// Which sparse Cholesky kernel to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FactorVariant {
    /// faer's choice by estimated flop ratio.
    #[default]
    Auto,
    /// Column-by-column (left-looking) factorisation.
    Simplicial,
    /// Dense supernodal blocks.
    Supernodal,
}

/// `A = LLᵀ` of a sparse symmetric positive definite matrix with a fill-reducing AMD ordering
/// (faer's symbolic + numeric factorisation, each done once), single-threaded: at these sizes
/// faer's parallel mode was measured slower (shared/DEPENDENCIES.md); parallelism goes over
/// frames and stages instead.
///
/// [`Factorization::solve_in_place`] reuses a workspace sized at construction for up to
/// [`Factorization::MAX_RHS_COLUMNS`] columns, so per-frame solves allocate nothing.
pub struct Factorization {
    symbolic: Arc<SymbolicCholesky<usize>>,
    values: Vec<f64>,
    workspace: MemBuffer,
    n: usize,
}

impl std::fmt::Debug for Factorization {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Factorization")
            .field("n", &self.n)
            .field("factor_nnz", &self.values.len())
            .finish()
    }
}

impl Factorization {
    /// Right-hand-side columns a solve can take without allocating (x, y, z).
    pub const MAX_RHS_COLUMNS: usize = 3;

    /// Factors `a` (both triangles stored; the lower one is read) with faer's automatic choice
    /// of kernel.
    pub fn new(a: &SparseMatrix) -> Result<Self, FemError> {
        Self::with_variant(a, FactorVariant::Auto)
    }

    /// Factors `a` with the given kernel and AMD ordering.
    pub fn with_variant(a: &SparseMatrix, variant: FactorVariant) -> Result<Self, FemError> {
        Self::with_options(a, variant, None)
    }

    /// Factors `a` with the given kernel and fill-reducing order: `order[k]` is the unknown
    /// eliminated k-th (e.g. from [`crate::nested_dissection`]); `None` selects AMD.
    pub fn with_options(
        a: &SparseMatrix,
        variant: FactorVariant,
        order: Option<&[usize]>,
    ) -> Result<Self, FemError> {
        let n = a.nrows();
        let inverse: Option<Vec<usize>> = match order {
            Some(order) => {
                let mut inv = vec![usize::MAX; n];
                if order.len() != n {
                    return Err(FemError::Dimension {
                        what: "elimination order length",
                        expected: n,
                        got: order.len(),
                    });
                }
                for (k, &i) in order.iter().enumerate() {
                    if i >= n || inv[i] != usize::MAX {
                        return Err(FemError::Assembly {
                            reason: format!(
                                "elimination order is not a permutation (entry {k} = {i})"
                            ),
                        });
                    }
                    inv[i] = k;
                }
                Some(inv)
            }
            None => None,
        };
        let ordering = match (order, &inverse) {
            (Some(fwd), Some(inv)) => SymmetricOrdering::Custom(PermRef::new_checked(fwd, inv, n)),
            _ => SymmetricOrdering::Amd,
        };
        let threshold = match variant {
            FactorVariant::Auto => SupernodalThreshold::AUTO,
            FactorVariant::Simplicial => SupernodalThreshold::FORCE_SIMPLICIAL,
            FactorVariant::Supernodal => SupernodalThreshold::FORCE_SUPERNODAL,
        };
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            ordering,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: threshold,
                ..Default::default()
            },
        )
        .map_err(|e| FemError::Assembly {
            reason: format!("symbolic Cholesky: {e:?}"),
        })?;
        Self::numeric(Arc::new(symbolic), a)
    }

    /// Factors `a`, which must have the same sparsity pattern as the matrix this factorisation
    /// was built from, reusing its symbolic analysis (ordering and elimination tree).
    pub fn with_same_pattern(&self, a: &SparseMatrix) -> Result<Self, FemError> {
        Self::numeric(Arc::clone(&self.symbolic), a)
    }

    /// Number of numeric factorisations this process has computed so far: lets a test or a
    /// benchmark check that a clip is factored once and each frame only solves.
    pub fn numeric_count() -> usize {
        NUMERIC_FACTORIZATIONS.load(Ordering::Relaxed)
    }

    fn numeric(symbolic: Arc<SymbolicCholesky<usize>>, a: &SparseMatrix) -> Result<Self, FemError> {
        NUMERIC_FACTORIZATIONS.fetch_add(1, Ordering::Relaxed);
        let n = a.nrows();
        if symbolic.nrows() != n {
            return Err(FemError::Dimension {
                what: "matrix order for the shared symbolic factorisation",
                expected: symbolic.nrows(),
                got: n,
            });
        }
        let mut values = vec![0.0; symbolic.len_val()];
        let mut scratch = MemBuffer::new(
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
        );
        symbolic
            .factorize_numeric_llt(
                &mut values,
                a.as_ref(),
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut scratch),
                Default::default(),
            )
            .map_err(|e| FemError::NotPositiveDefinite {
                reason: match e {
                    faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                        format!("the factorisation met a pivot ≤ 0 at row {index}")
                    }
                },
            })?;
        let workspace =
            MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(Self::MAX_RHS_COLUMNS, Par::Seq));
        Ok(Factorization {
            symbolic,
            values,
            workspace,
            n,
        })
    }

    /// Number of stored values of the factor L (the fill).
    pub fn factor_nnz(&self) -> usize {
        self.values.len()
    }

    /// Order of the matrix.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Overwrites `rhs` (n × c, c ≤ 3) with `A⁻¹ rhs`. Allocates nothing.
    ///
    /// # Panics
    /// If `rhs` has the wrong number of rows or more than [`Self::MAX_RHS_COLUMNS`] columns.
    #[track_caller]
    pub fn solve_in_place(&mut self, rhs: MatMut<'_, f64>) {
        assert!(rhs.nrows() == self.n && rhs.ncols() <= Self::MAX_RHS_COLUMNS);
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut self.workspace),
        );
    }
}
