//! The fusion system: operators, weights and the two pre-factored frame matrices.

use std::time::Instant;

use faer::{MatMut, MatRef};

use crate::sparse::{linear_combination, sym_matmul, SparseMatrix};
use crate::{Factorization, FemError};

/// Regularisation weights of the combined energy (unnumbered, after Eq. 2.5):
/// `E = E_data + λ E_smooth + μ E_temp`.
///
/// Defaults: λ = 10, μ = 0.5, the best RMSE of the ground-truth benchmark's λ × μ sweep
/// (`visage eval synthetic --sweep-lambda … --sweep-mu …`, 3 sequences × 120 frames, cnn-like
/// noise, moving heads: 1.96 mm RMSE, 3.8 mm/frame jitter vs raw 2.20 / 6.06). The paper's
/// λ = 2.5, μ = 12.5 (ERRATA 6) lag ~13 frames under head motion on the image-plane mesh
/// (7.5 mm RMSE, ERRATA 15).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Weights {
    /// Smoothness weight λ, in reference pixels⁴ (see [`crate::domain`]). Default 10 (paper 2.5).
    pub lambda: f64,
    /// Temporal weight μ (dimensionless). Default 0.5 (paper 12.5).
    pub mu: f64,
}

impl Default for Weights {
    fn default() -> Self {
        Weights {
            lambda: 10.0,
            mu: 0.5,
        }
    }
}

/// The largest λ or μ accepted: beyond it the data term has no weight left in double
/// precision and the factorisation fails.
pub const MAX_WEIGHT: f64 = 1e6;

impl Weights {
    /// Errors unless both weights are finite, non-negative and at most [`MAX_WEIGHT`].
    pub fn validate(&self) -> Result<(), FemError> {
        for (name, value) in [("lambda", self.lambda), ("mu", self.mu)] {
            if !(value.is_finite() && (0.0..=MAX_WEIGHT).contains(&value)) {
                return Err(FemError::InvalidWeight { name, value });
            }
        }
        Ok(())
    }
}

/// The constant matrices of a sequence (#V × #V each).
#[derive(Clone, Debug)]
pub struct Operators {
    /// Consistent mass M (temporal term).
    pub mass: SparseMatrix,
    /// Data mass M_D (pixel quadrature of the data term, see [`crate::PixelQuadrature`]).
    pub data_mass: SparseMatrix,
    /// Biharmonic stiffness K = Lᵀ M_l⁻¹ L.
    pub biharmonic: SparseMatrix,
}

/// The frame matrices, factored once per sequence:
/// - `A = M_D + λK + μM`, the streaming matrix (ERRATA 4): `A s^k = b^k + μ M s^{k−1}`;
/// - `A₀ = M_D + λK`, for a frame without a usable predecessor (first frame, cut, lost
///   track; ERRATA 18), factored with `A`'s symbolic analysis (same pattern).
#[derive(Debug)]
pub struct FusionSystem {
    pub ops: Operators,
    pub weights: Weights,
    a_temporal: SparseMatrix,
    a_reset: SparseMatrix,
    pub(crate) factor_temporal: Factorization,
    pub(crate) factor_reset: Factorization,
    factor_seconds: f64,
}

impl FusionSystem {
    /// Assembles and factors both frame matrices.
    pub fn new(ops: Operators, weights: Weights) -> Result<Self, FemError> {
        weights.validate()?;
        let n = ops.mass.nrows();
        for (what, m) in [
            ("data mass", &ops.data_mass),
            ("biharmonic", &ops.biharmonic),
        ] {
            if m.nrows() != n {
                return Err(FemError::Dimension {
                    what,
                    expected: n,
                    got: m.nrows(),
                });
            }
        }
        let (l, mu) = (weights.lambda, weights.mu);
        let a_temporal =
            linear_combination(&[(1.0, &ops.data_mass), (l, &ops.biharmonic), (mu, &ops.mass)])?;
        // Same pattern as `a_temporal` (M's entries kept with weight 0) so the symbolic
        // analysis is shared.
        let a_reset = linear_combination(&[
            (1.0, &ops.data_mass),
            (l, &ops.biharmonic),
            (0.0, &ops.mass),
        ])?;
        if a_reset.symbolic().col_ptr() != a_temporal.symbolic().col_ptr()
            || a_reset.symbolic().row_idx() != a_temporal.symbolic().row_idx()
        {
            return Err(FemError::Assembly {
                reason: "reset and streaming matrices have different sparsity patterns".into(),
            });
        }
        let start = Instant::now();
        let factor_temporal = Factorization::new(&a_temporal)?;
        let factor_reset = factor_temporal.with_same_pattern(&a_reset)?;
        let factor_seconds = start.elapsed().as_secs_f64();
        Ok(FusionSystem {
            ops,
            weights,
            a_temporal,
            a_reset,
            factor_temporal,
            factor_reset,
            factor_seconds,
        })
    }

    /// Number of vertices.
    pub fn dim(&self) -> usize {
        self.ops.mass.nrows()
    }

    /// Stored values of the Cholesky factor of `A`.
    pub fn factor_nnz(&self) -> usize {
        self.factor_temporal.factor_nnz()
    }

    /// Wall time of the symbolic + both numeric factorisations, seconds.
    pub fn factor_seconds(&self) -> f64 {
        self.factor_seconds
    }

    /// The streaming matrix `A = M_D + λK + μM`.
    pub fn matrix_temporal(&self) -> &SparseMatrix {
        &self.a_temporal
    }

    /// The reset matrix `A₀ = M_D + λK`.
    pub fn matrix_reset(&self) -> &SparseMatrix {
        &self.a_reset
    }

    /// `y ← A x` (temporal) or `y ← A₀ x`; x, y #V × 3.
    pub fn apply(&self, temporal: bool, x: MatRef<'_, f64>, y: MatMut<'_, f64>) {
        let a = if temporal {
            &self.a_temporal
        } else {
            &self.a_reset
        };
        sym_matmul(a, x, 1.0, 0.0, y);
    }

    /// `y ← α M x + β y`.
    pub fn apply_mass(&self, x: MatRef<'_, f64>, alpha: f64, beta: f64, y: MatMut<'_, f64>) {
        sym_matmul(&self.ops.mass, x, alpha, beta, y);
    }
}
