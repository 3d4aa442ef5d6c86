//! Box-constrained convex quadratic programs: `min ½ xᵀQx − cᵀx` subject to `lo ≤ x ≤ hi`,
//! `Q` symmetric positive definite — the expression weights' solve, bounded to [0, 1] as the
//! blendshapes are meant (not clamped after an unconstrained solve, which would leave the other
//! weights compensating for the clipped one).
//!
//! A primal active-set method (Nocedal and Wright, *Numerical Optimization*, Algorithm 16.3,
//! specialised to bounds, as in Stark and Parker's bounded-variable least squares): the
//! variables are split into free ones and ones held at a bound; the free ones are solved
//! exactly (Cholesky of their block), a step that would leave the box stops at the first bound
//! it meets and holds that variable there, and a held variable whose gradient points into the
//! box is released. Every step lowers the objective, so no split repeats and the method ends at
//! the exact minimiser. The split is kept from one call to the next: a video's consecutive
//! frames hold nearly the same weights at zero, so a frame costs one or two factorisations of
//! the free block.

use faer::MatRef;

/// Active-set changes at most (a safeguard: each change lowers the objective).
pub const MAX_STEPS: usize = 500;

/// A held variable is released when, alone, it would move into the box by more than this (in
/// the variables' units).
pub const TOLERANCE: f64 = 1e-9;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Bound {
    Free,
    Lower,
    Upper,
}

/// `(Q x)_i` for symmetric `Q` (its column i is its row i, and columns are contiguous).
fn dot_col(q: MatRef<'_, f64>, i: usize, x: &[f64]) -> f64 {
    q.col(i).iter().zip(x).map(|(a, b)| a * b).sum()
}

/// A box-constrained QP solver with its scratch space (sized once).
#[derive(Clone, Debug)]
pub struct BoxQp {
    state: Vec<Bound>,
    free: Vec<usize>,
    factor: Vec<f64>,
    rhs: Vec<f64>,
    target: Vec<f64>,
    gradient: Vec<f64>,
}

impl BoxQp {
    /// A solver for `n` variables.
    pub fn new(n: usize) -> BoxQp {
        BoxQp {
            state: vec![Bound::Free; n],
            free: Vec::with_capacity(n),
            factor: vec![0.0; n * n],
            rhs: vec![0.0; n],
            target: vec![0.0; n],
            gradient: vec![0.0; n],
        }
    }

    /// Minimises `½ xᵀQx − cᵀx` over `lo ≤ x ≤ hi`, starting from `x` (clamped into the box)
    /// and from the previous call's split (variables at a bound there and here stay held).
    /// Returns the active-set steps taken.
    ///
    /// # Panics
    /// If the sizes disagree with each other or with [`BoxQp::new`]'s `n`.
    #[track_caller]
    pub fn solve(
        &mut self,
        q: MatRef<'_, f64>,
        c: &[f64],
        lo: f64,
        hi: f64,
        x: &mut [f64],
    ) -> usize {
        let n = x.len();
        assert!(
            q.nrows() == n && q.ncols() == n && c.len() == n && self.state.len() == n,
            "sizes differ"
        );
        for (v, s) in x.iter_mut().zip(&mut self.state) {
            *v = v.clamp(lo, hi);
            *s = if *v <= lo {
                Bound::Lower
            } else if *v >= hi {
                Bound::Upper
            } else {
                Bound::Free
            };
        }
        for step in 1..=MAX_STEPS {
            self.free.clear();
            self.free
                .extend((0..n).filter(|&i| self.state[i] == Bound::Free));
            // The free block's minimiser with the held variables fixed, as a step from x.
            for (i, g) in self.gradient.iter_mut().enumerate() {
                *g = dot_col(q, i, x) - c[i];
            }
            if !self.newton_step(q) {
                return step; // not positive definite: keep the feasible point reached
            }
            // The largest part of the step that stays in the box.
            let (mut alpha, mut blocking) = (1.0f64, None);
            for &i in &self.free {
                let (from, to) = (x[i], x[i] + self.target[i]);
                let (limit, bound) = if to < lo {
                    ((from - lo) / (from - to), Bound::Lower)
                } else if to > hi {
                    ((hi - from) / (to - from), Bound::Upper)
                } else {
                    continue;
                };
                if limit < alpha {
                    alpha = limit.max(0.0);
                    blocking = Some((i, bound));
                }
            }
            for &i in &self.free {
                x[i] += alpha * self.target[i];
            }
            if let Some((i, bound)) = blocking {
                x[i] = if bound == Bound::Lower { lo } else { hi };
                self.state[i] = bound;
                continue;
            }
            // At the free minimiser: release the held variable whose gradient points into the
            // box the most, or stop.
            let mut release = None;
            let mut strongest = 0.0;
            for i in 0..n {
                let inward = match self.state[i] {
                    Bound::Free => continue,
                    Bound::Lower => c[i] - dot_col(q, i, x),
                    Bound::Upper => dot_col(q, i, x) - c[i],
                };
                // Scaled by the diagonal: how far the variable would move on its own.
                let inward = inward / q[(i, i)];
                if inward > strongest {
                    strongest = inward;
                    release = Some(i);
                }
            }
            match release {
                Some(i) if strongest > TOLERANCE => self.state[i] = Bound::Free,
                _ => return step,
            }
        }
        MAX_STEPS
    }

    /// The Newton direction of the free block, `Q_FF d_F = −g_F`, into `target` (Cholesky).
    /// False when the block is not positive definite.
    fn newton_step(&mut self, q: MatRef<'_, f64>) -> bool {
        let f = &self.free;
        let m = f.len();
        for (a, &i) in f.iter().enumerate() {
            self.rhs[a] = -self.gradient[i];
            for (b, &j) in f.iter().enumerate().take(a + 1) {
                self.factor[a * m + b] = q[(i, j)];
            }
        }
        // In-place Cholesky, lower triangle, row-major m × m.
        for a in 0..m {
            for b in 0..=a {
                let mut s = self.factor[a * m + b];
                for k in 0..b {
                    s -= self.factor[a * m + k] * self.factor[b * m + k];
                }
                if a == b {
                    if s <= 0.0 {
                        return false;
                    }
                    self.factor[a * m + a] = s.sqrt();
                } else {
                    self.factor[a * m + b] = s / self.factor[b * m + b];
                }
            }
        }
        // L y = rhs, then Lᵀ z = y.
        for a in 0..m {
            let mut s = self.rhs[a];
            for k in 0..a {
                s -= self.factor[a * m + k] * self.rhs[k];
            }
            self.rhs[a] = s / self.factor[a * m + a];
        }
        for a in (0..m).rev() {
            let mut s = self.rhs[a];
            for k in a + 1..m {
                s -= self.factor[k * m + a] * self.rhs[k];
            }
            self.rhs[a] = s / self.factor[a * m + a];
        }
        for (a, &i) in f.iter().enumerate() {
            self.target[i] = self.rhs[a];
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;

    fn solve(q: &Mat<f64>, c: &[f64], x: &mut [f64]) -> usize {
        BoxQp::new(x.len()).solve(q.as_ref(), c, 0.0, 1.0, x)
    }

    #[test]
    fn interior_minimum_is_the_linear_solution() {
        let q = Mat::from_fn(3, 3, |i, j| if i == j { 4.0 } else { 1.0 });
        let x_true = [0.2, 0.5, 0.7];
        let c: Vec<f64> = (0..3)
            .map(|i| (0..3).map(|j| q[(i, j)] * x_true[j]).sum())
            .collect();
        let mut x = [0.0; 3];
        solve(&q, &c, &mut x);
        for i in 0..3 {
            assert!((x[i] - x_true[i]).abs() < 1e-12, "{x:?}");
        }
    }

    #[test]
    fn the_bound_is_active_and_the_rest_adjusts() {
        // The unconstrained minimum is (2, 0); clamping it gives (1, 0), but with x0 held at
        // its bound the best x1 is (c₁ − x0)/2 = 0.5.
        let q = Mat::from_fn(2, 2, |i, j| [[2.0, 1.0], [1.0, 2.0]][i][j]);
        let c = [4.0, 2.0];
        let mut x = [0.5, 0.5];
        solve(&q, &c, &mut x);
        assert!(
            (x[0] - 1.0).abs() < 1e-12 && (x[1] - 0.5).abs() < 1e-12,
            "{x:?}"
        );
    }

    #[test]
    fn matches_brute_force_on_random_problems() {
        // Small problems checked against enumerating every active set with the KKT conditions.
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..200 {
            let n = 5;
            let b = Mat::from_fn(n + 2, n, |_, _| rnd());
            let q = Mat::from_fn(n, n, |i, j| {
                (0..n + 2).map(|k| b[(k, i)] * b[(k, j)]).sum::<f64>() + 0.1 * (i == j) as u8 as f64
            });
            let c: Vec<f64> = (0..n).map(|_| 3.0 * rnd()).collect();
            let mut x: Vec<f64> = (0..n).map(|_| rnd().abs()).collect();
            solve(&q, &c, &mut x);
            let objective = |x: &[f64]| {
                0.5 * (0..n)
                    .map(|i| (0..n).map(|j| x[i] * q[(i, j)] * x[j]).sum::<f64>())
                    .sum::<f64>()
                    - (0..n).map(|i| c[i] * x[i]).sum::<f64>()
            };
            // KKT: gradient zero on free variables, pointing outward at the bounds.
            for i in 0..n {
                let g = (0..n).map(|j| q[(i, j)] * x[j]).sum::<f64>() - c[i];
                if x[i] <= 0.0 {
                    assert!(g >= -1e-9, "{g}");
                } else if x[i] >= 1.0 {
                    assert!(g <= 1e-9, "{g}");
                } else {
                    assert!(g.abs() < 1e-9, "{g}");
                }
            }
            // And no random feasible point does better.
            for _ in 0..50 {
                let y: Vec<f64> = (0..n).map(|_| rnd().abs()).collect();
                assert!(objective(&x) <= objective(&y) + 1e-12);
            }
        }
    }
}
