//! The discrete combined energy (the paper's unnumbered functional after Eq. 2.5), up to a constant that does not depend on the surface.
//!
//! With `s^k` the vertex positions (#V × 3) and `b^k` the data right-hand sides,
//! `E = Σ_k [ s^kᵀ M_D s^k − 2 b^kᵀ s^k + λ s^kᵀ K s^k ] + μ Σ_{k≥1} (s^k − s^{k−1})ᵀ M (s^k − s^{k−1})`
//! (summed over the three coordinate columns). It differs from the continuous energy by
//! `Σ_p w |D ρ|²`, the same for every candidate surface, so it orders candidates correctly.

use faer::{Mat, MatRef};

use crate::sparse::{sym_matmul, SparseMatrix};
use crate::FusionSystem;

fn quadratic(a: &SparseMatrix, x: MatRef<'_, f64>) -> f64 {
    let mut y = Mat::<f64>::zeros(x.nrows(), x.ncols());
    sym_matmul(a, x, 1.0, 0.0, y.as_mut());
    inner(x, y.as_ref())
}

fn inner(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> f64 {
    let mut s = 0.0;
    for c in 0..a.ncols() {
        for i in 0..a.nrows() {
            s += a[(i, c)] * b[(i, c)];
        }
    }
    s
}

/// Energy of one frame: data + smoothness, plus `μ‖s − previous‖²_M` when a predecessor is given
/// (the quantity a streaming step minimises).
pub fn frame_energy(
    system: &FusionSystem,
    s: MatRef<'_, f64>,
    b: MatRef<'_, f64>,
    previous: Option<MatRef<'_, f64>>,
) -> f64 {
    let ops = &system.ops;
    let mut e = quadratic(&ops.data_mass, s) - 2.0 * inner(b, s)
        + system.weights.lambda * quadratic(&ops.biharmonic, s);
    if let Some(prev) = previous {
        let mut d = s.to_owned();
        d -= prev;
        e += system.weights.mu * quadratic(&ops.mass, d.as_ref());
    }
    e
}

/// Energy of a whole clip (the quantity clip mode minimises).
pub fn clip_energy(system: &FusionSystem, s: &[Mat<f64>], b: &[Mat<f64>]) -> f64 {
    let mut e = 0.0;
    for k in 0..s.len() {
        let prev = (k > 0).then(|| s[k - 1].as_ref());
        e += frame_energy(system, s[k].as_ref(), b[k].as_ref(), prev);
    }
    e
}
