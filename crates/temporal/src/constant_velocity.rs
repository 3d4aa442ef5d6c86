//! The constant-velocity Kalman filter: each scalar is a position with a velocity, driven by
//! white (piecewise-constant) acceleration and seen through white measurement noise.
//!
//! Every scalar of a track has the same model and is updated at the same times, so all share
//! one 2 × 2 covariance; the state is two numbers per scalar. Only the ratio of the
//! acceleration noise to the measurement noise sets the gains, so the filter has one
//! parameter and works in any unit.

use crate::TrackFilter;

/// The velocity's variance before two samples are seen (measurement variances per s²): loose, so
/// that the second sample sets the speed.
const UNKNOWN_SPEED_VARIANCE: f64 = 1e6;

/// Constant-velocity Kalman filter.
#[derive(Clone, Debug)]
pub struct ConstantVelocity {
    /// Acceleration noise over measurement noise, σ_a / σ_z (1/s²): larger follows faster
    /// motion with less lag and smooths less.
    pub accel_ratio: f64,
    x: Vec<f64>,
    v: Vec<f64>,
    /// Covariance of (position, velocity) in units of the measurement variance.
    p: [[f64; 2]; 2],
}

impl ConstantVelocity {
    pub fn new(accel_ratio: f64) -> ConstantVelocity {
        ConstantVelocity {
            accel_ratio,
            x: Vec::new(),
            v: Vec::new(),
            p: [[1.0, 0.0], [0.0, 0.0]],
        }
    }

    /// Predicts and updates the covariance for a step of `dt`; returns the gains (position,
    /// velocity) and the predicted covariance.
    fn update_covariance(&mut self, dt: f64) -> ([f64; 2], [[f64; 2]; 2]) {
        let [[a, b], [_, d]] = self.p;
        // Predict: P ← F P Fᵀ + Q, F = [[1, dt], [0, 1]], Q = σ² [[dt⁴/4, dt³/2], [dt³/2, dt²]].
        let q = (self.accel_ratio * dt).powi(2);
        let pa = a + 2.0 * dt * b + dt * dt * d + q * dt * dt / 4.0;
        let pb = b + dt * d + q * dt / 2.0;
        let pd = d + q;
        // Update with a unit-variance measurement of the position.
        let s = pa + 1.0;
        let k = [pa / s, pb / s];
        self.p = [
            [(1.0 - k[0]) * pa, (1.0 - k[0]) * pb],
            [(1.0 - k[0]) * pb, pd - k[1] * pb],
        ];
        (k, [[pa, pb], [pb, pd]])
    }

    /// One step; returns the predicted covariance (`None` on a first sample).
    pub(crate) fn advance(&mut self, x: &[f64], dt: f64) -> Option<[[f64; 2]; 2]> {
        if self.x.len() != x.len() || dt <= 0.0 {
            self.x = x.to_vec();
            self.v = vec![0.0; x.len()];
            // The first position is as good as a measurement; the velocity is unknown.
            self.p = [[1.0, 0.0], [0.0, UNKNOWN_SPEED_VARIANCE]];
            return None;
        }
        let ([kx, kv], predicted) = self.update_covariance(dt);
        for ((p, v), &z) in self.x.iter_mut().zip(&mut self.v).zip(x) {
            let prediction = *p + dt * *v;
            let innovation = z - prediction;
            *p = prediction + kx * innovation;
            *v += kv * innovation;
        }
        Some(predicted)
    }

    /// The filtered positions, velocities and covariance.
    pub(crate) fn state(&self) -> (&[f64], &[f64], [[f64; 2]; 2]) {
        (&self.x, &self.v, self.p)
    }
}

impl TrackFilter for ConstantVelocity {
    fn step(&mut self, x: &[f64], dt: f64) -> &[f64] {
        self.advance(x, dt);
        &self.x
    }

    fn reset(&mut self) {
        self.x.clear();
        self.v.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ramp_is_followed_without_lag_once_settled() {
        let mut f = ConstantVelocity::new(10.0);
        let mut error = 0.0;
        for t in 0..300 {
            let x = 0.5 * t as f64;
            error = x - f.step(&[x], 1.0 / 30.0)[0];
        }
        assert!(error.abs() < 1e-6, "lag {error}");
    }

    #[test]
    fn more_acceleration_noise_smooths_less() {
        // White noise in: the output's variance grows with the ratio.
        let noise: Vec<f64> = (0..2000)
            .map(|i| ((i as f64 * 12.9898).sin() * 43758.5453).fract() - 0.5)
            .collect();
        let out_var = |ratio: f64| {
            let mut f = ConstantVelocity::new(ratio);
            let y: Vec<f64> = noise.iter().map(|&n| f.step(&[n], 1.0 / 30.0)[0]).collect();
            y[100..].iter().map(|v| v * v).sum::<f64>() / (y.len() - 100) as f64
        };
        let (low, high) = (out_var(30.0), out_var(3000.0));
        let input = noise[100..].iter().map(|v| v * v).sum::<f64>() / (noise.len() - 100) as f64;
        assert!(low < high && high < input, "{low} {high} {input}");
    }
}
