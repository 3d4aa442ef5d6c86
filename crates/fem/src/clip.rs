//! Clip mode: the exact minimiser of the whole-sequence energy (ERRATA 1, 4, 5).
//!
//! With every frame known, the minimiser of Σ_k [E_data^k + λ E_smooth^k] + μ Σ_k ‖s^k − s^{k−1}‖²_M
//! solves the block-tridiagonal system
//! `(M_D + λK + c_k μM) s^k − μM (s^{k−1} + s^{k+1}) = b^k`, with `c_k = 2` inside the clip and
//! `c_k = 1` at its ends (ERRATA 1). It is symmetric positive definite: the temporal part is a
//! path-graph Laplacian ⊗ M (ERRATA 5). We solve it with preconditioned conjugate gradients;
//! the preconditioner is block-diagonal with the pre-factored streaming matrix
//! `A = M_D + λK + μM` on every block — exact for the two end frames, and spectrally equivalent
//! inside — so nothing is refactored.

use faer::Mat;

use crate::sparse::sym_matmul;
use crate::FusionSystem;

/// Stopping rule of the clip solver.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ClipOptions {
    /// Stop when `‖b − 𝒜 s‖ / ‖b‖ ≤ tolerance` over the whole clip (Frobenius norms).
    pub tolerance: f64,
    /// Give up after this many iterations (reported as not converged).
    pub max_iterations: usize,
}

impl Default for ClipOptions {
    fn default() -> Self {
        ClipOptions {
            tolerance: 1e-8,
            max_iterations: 1000,
        }
    }
}

/// Outcome of a clip solve.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ClipReport {
    /// PCG iterations run.
    pub iterations: usize,
    /// Final `‖b − 𝒜 s‖ / ‖b‖`, recomputed from the solution.
    pub relative_residual: f64,
    /// Whether the tolerance was met.
    pub converged: bool,
}

/// Applies the block-tridiagonal clip operator: `y_k = A₀ x_k + μ M (c_k x_k − x_{k−1} − x_{k+1})`.
pub fn apply_clip_operator(
    system: &FusionSystem,
    x: &[Mat<f64>],
    y: &mut [Mat<f64>],
    temp: &mut Mat<f64>,
) {
    let t = x.len();
    let mu = system.weights.mu;
    for k in 0..t {
        system.apply(false, x[k].as_ref(), y[k].as_mut());
        if mu == 0.0 || t == 1 {
            continue;
        }
        temp.fill(0.0);
        for nb in [k.wrapping_sub(1), k + 1] {
            if nb < t {
                for c in 0..3 {
                    for i in 0..x[k].nrows() {
                        temp[(i, c)] += x[k][(i, c)] - x[nb][(i, c)];
                    }
                }
            }
        }
        sym_matmul(&system.ops.mass, temp.as_ref(), mu, 1.0, y[k].as_mut());
    }
}

fn dot(a: &[Mat<f64>], b: &[Mat<f64>]) -> f64 {
    let mut s = 0.0;
    for (x, y) in a.iter().zip(b) {
        for c in 0..x.ncols() {
            for i in 0..x.nrows() {
                s += x[(i, c)] * y[(i, c)];
            }
        }
    }
    s
}

fn axpy(alpha: f64, x: &[Mat<f64>], y: &mut [Mat<f64>]) {
    for (x, y) in x.iter().zip(y.iter_mut()) {
        for c in 0..x.ncols() {
            for i in 0..x.nrows() {
                y[(i, c)] += alpha * x[(i, c)];
            }
        }
    }
}

/// Solves the clip system for all frames: `b[k]` are the data right-hand sides (#V × 3 each);
/// `x` holds the initial guess on entry (e.g. the streaming solutions) and the solution on exit.
///
/// # Panics
/// If `b` and `x` differ in length or a block is not #V × 3.
#[track_caller]
pub fn solve_clip(
    system: &mut FusionSystem,
    b: &[Mat<f64>],
    x: &mut [Mat<f64>],
    options: &ClipOptions,
) -> ClipReport {
    let n = system.dim();
    assert!(b.len() == x.len());
    assert!(b
        .iter()
        .chain(x.iter())
        .all(|m| m.nrows() == n && m.ncols() == 3));
    let t = b.len();
    let zeros = || (0..t).map(|_| Mat::<f64>::zeros(n, 3)).collect::<Vec<_>>();
    let (mut r, mut z, mut q) = (zeros(), zeros(), zeros());
    let mut temp = Mat::<f64>::zeros(n, 3);
    let b_norm = dot(b, b).sqrt().max(f64::MIN_POSITIVE);

    apply_clip_operator(system, x, &mut q, &mut temp);
    for k in 0..t {
        r[k].copy_from(&b[k]);
    }
    axpy(-1.0, &q, &mut r);
    let precondition = |system: &mut FusionSystem, r: &[Mat<f64>], z: &mut [Mat<f64>]| {
        for (rk, zk) in r.iter().zip(z.iter_mut()) {
            zk.copy_from(rk);
            let factor = if t == 1 {
                &mut system.factor_reset
            } else {
                &mut system.factor_temporal
            };
            factor.solve_in_place(zk.as_mut());
        }
    };
    precondition(system, &r, &mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut iterations = 0;
    while iterations < options.max_iterations && dot(&r, &r).sqrt() / b_norm > options.tolerance {
        apply_clip_operator(system, &p, &mut q, &mut temp);
        let pq = dot(&p, &q);
        if pq <= 0.0 {
            break;
        }
        let alpha = rz / pq;
        axpy(alpha, &p, x);
        axpy(-alpha, &q, &mut r);
        precondition(system, &r, &mut z);
        let rz_next = dot(&r, &z);
        let beta = rz_next / rz;
        rz = rz_next;
        for (pk, zk) in p.iter_mut().zip(&z) {
            for c in 0..3 {
                for i in 0..n {
                    pk[(i, c)] = zk[(i, c)] + beta * pk[(i, c)];
                }
            }
        }
        iterations += 1;
    }
    // True residual, not the recurrence's.
    apply_clip_operator(system, x, &mut q, &mut temp);
    for k in 0..t {
        r[k].copy_from(&b[k]);
    }
    axpy(-1.0, &q, &mut r);
    let relative_residual = dot(&r, &r).sqrt() / b_norm;
    ClipReport {
        iterations,
        relative_residual,
        converged: relative_residual <= options.tolerance,
    }
}
