//! The One-Euro filter (Casiez, Roussel and Vogel, CHI 2012): an exponential smoother whose
//! cut-off frequency rises with the signal's speed, `f_c = f_min + β |ẋ|`, so that slow
//! motion is smoothed hard and fast motion follows with little lag.

use std::f64::consts::PI;

use crate::TrackFilter;

/// One-Euro filter on every scalar of a track independently (the paper's form).
#[derive(Clone, Debug)]
pub struct OneEuro {
    /// Cut-off at rest, Hz.
    pub min_cutoff_hz: f64,
    /// Cut-off increase per unit of speed (1 / the signal's unit).
    pub beta: f64,
    /// Cut-off of the speed estimate, Hz.
    pub derivative_cutoff_hz: f64,
    y: Vec<f64>,
    dy: Vec<f64>,
}

/// The smoothing factor of a first-order low-pass at cut-off `fc` (Hz) sampled every `dt` s.
fn smoothing(fc: f64, dt: f64) -> f64 {
    let tau = 1.0 / (2.0 * PI * fc);
    1.0 / (1.0 + tau / dt)
}

impl OneEuro {
    /// The paper's defaults for the speed's cut-off (1 Hz).
    pub fn new(min_cutoff_hz: f64, beta: f64) -> OneEuro {
        OneEuro {
            min_cutoff_hz,
            beta,
            derivative_cutoff_hz: 1.0,
            y: Vec::new(),
            dy: Vec::new(),
        }
    }
}

impl TrackFilter for OneEuro {
    fn step(&mut self, x: &[f64], dt: f64) -> &[f64] {
        if self.y.len() != x.len() || dt <= 0.0 {
            self.y = x.to_vec();
            self.dy = vec![0.0; x.len()];
            return &self.y;
        }
        let a_d = smoothing(self.derivative_cutoff_hz, dt);
        for ((y, dy), &x) in self.y.iter_mut().zip(&mut self.dy).zip(x) {
            *dy += a_d * ((x - *y) / dt - *dy);
            let a = smoothing(self.min_cutoff_hz + self.beta * dy.abs(), dt);
            *y += a * (x - *y);
        }
        &self.y
    }

    fn reset(&mut self) {
        self.y.clear();
        self.dy.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_raises_the_cutoff() {
        // A ramp: with β = 0 the filter lags it by a fixed amount; with β > 0 the lag shrinks.
        let lag = |beta: f64| {
            let mut f = OneEuro::new(1.0, beta);
            let mut last = 0.0;
            for t in 0..200 {
                last = t as f64 - f.step(&[t as f64], 1.0 / 30.0)[0];
            }
            last
        };
        let (slow, fast) = (lag(0.0), lag(0.1));
        assert!(slow > 4.0 && fast < 0.5 * slow, "lag {slow} vs {fast}");
    }

    #[test]
    fn a_constant_passes_unchanged() {
        let mut f = OneEuro::new(0.5, 0.01);
        for _ in 0..10 {
            assert_eq!(f.step(&[2.0, -3.0], 0.04), &[2.0, -3.0]);
        }
    }
}
