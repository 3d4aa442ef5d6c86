//! Streaming (live-capture) fusion: one right-hand side per frame (ERRATA 4).

use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Mat, MatMut, MatRef};

use crate::FusionSystem;

/// What one streaming step did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepReport {
    /// `‖A s − rhs‖_F / ‖rhs‖_F` of the solved system.
    pub relative_residual: f64,
    /// Whether the temporal term was active (false on the first frame and after a reset).
    pub temporal: bool,
}

/// Frame-by-frame solver of `(M_D + λK + μM) s^k = b^k + μ M s^{k−1}`, each frame using only
/// the past (live capture). The first frame, and the first after [`StreamingSolver::reset`],
/// solves `(M_D + λK) s^k = b^k`. Both matrices are factored once, in
/// [`FusionSystem::new`]; a step computes one right-hand side, two triangular solves with three
/// columns and a residual check, and allocates nothing.
#[derive(Debug)]
pub struct StreamingSolver {
    system: FusionSystem,
    previous: Mat<f64>,
    has_previous: bool,
    rhs: Mat<f64>,
    work: Mat<f64>,
}

impl StreamingSolver {
    /// A solver with no history.
    pub fn new(system: FusionSystem) -> Self {
        let n = system.dim();
        StreamingSolver {
            system,
            previous: Mat::zeros(n, 3),
            has_previous: false,
            rhs: Mat::zeros(n, 3),
            work: Mat::zeros(n, 3),
        }
    }

    /// The pre-factored system.
    pub fn system(&self) -> &FusionSystem {
        &self.system
    }

    /// The pre-factored system, mutably (the clip solver reuses its factorisations).
    pub fn system_mut(&mut self) -> &mut FusionSystem {
        &mut self.system
    }

    /// Forgets the history: the next frame is solved without the temporal term (shot cut, lost
    /// track; ERRATA 18).
    pub fn reset(&mut self) {
        self.has_previous = false;
    }

    /// The last solution (#V × 3), if any.
    pub fn previous(&self) -> Option<MatRef<'_, f64>> {
        self.has_previous.then(|| self.previous.as_ref())
    }

    /// Solves frame k from its data right-hand side `b` (#V × 3) into `out` (#V × 3) and keeps
    /// the solution as the next frame's predecessor.
    ///
    /// # Panics
    /// If `b` or `out` is not #V × 3.
    #[track_caller]
    pub fn step(&mut self, b: MatRef<'_, f64>, mut out: MatMut<'_, f64>) -> StepReport {
        let n = self.system.dim();
        assert!(b.nrows() == n && b.ncols() == 3 && out.nrows() == n && out.ncols() == 3);
        let temporal = self.has_previous && self.system.weights.mu > 0.0;
        self.rhs.copy_from(b);
        if temporal {
            self.system.apply_mass(
                self.previous.as_ref(),
                self.system.weights.mu,
                1.0,
                self.rhs.as_mut(),
            );
        }
        out.copy_from(&self.rhs);
        let factor = if temporal {
            &mut self.system.factor_temporal
        } else {
            &mut self.system.factor_reset
        };
        factor.solve_in_place(out.rb_mut());
        self.system.apply(temporal, out.rb(), self.work.as_mut());
        let relative_residual = relative_difference(self.work.as_ref(), self.rhs.as_ref());
        self.previous.copy_from(out.rb());
        self.has_previous = true;
        StepReport {
            relative_residual,
            temporal,
        }
    }

    /// Records `solution` as the predecessor without solving (a frame carried over, e.g. one
    /// with no valid depth).
    pub fn carry(&mut self, solution: MatRef<'_, f64>) {
        self.previous.copy_from(solution);
        self.has_previous = true;
    }
}

/// `‖a − b‖_F / ‖b‖_F` (or `‖a‖_F` when `b = 0`).
pub(crate) fn relative_difference(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for c in 0..a.ncols() {
        for i in 0..a.nrows() {
            let d = a[(i, c)] - b[(i, c)];
            num += d * d;
            den += b[(i, c)] * b[(i, c)];
        }
    }
    if den > 0.0 {
        (num / den).sqrt()
    } else {
        num.sqrt()
    }
}
