//! The filters a user could put on the per-frame surface's vertices instead of fusing: each
//! vertex's position (millimetres) through an EMA, a One-Euro filter, the constant-velocity
//! Kalman filter (causal) or a centred Gaussian (offline), from `visage-temporal`. Each
//! family's parameter is the best-RMSE value of a sweep on the quick benchmark
//! (docs/performance.md, "Temporal stability").

use faer::Mat;
use visage_temporal::{filter_track, gaussian_smooth, ConstantVelocity, Ema, OneEuro, TrackFilter};

/// Frame interval of the synthetic sequences, seconds (30 fps).
pub const SYNTHETIC_FRAME_INTERVAL_S: f64 = 1.0 / 30.0;

/// A baseline filter on the vertices' tracks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexFilter {
    /// Exponential moving average, α = [`EMA_ALPHA`].
    Ema,
    /// One-Euro, [`ONE_EURO_MIN_CUTOFF_HZ`], [`ONE_EURO_BETA`] (per mm/s).
    OneEuro,
    /// Constant-velocity Kalman filter, [`KALMAN_RATIO`].
    Kalman,
    /// Centred Gaussian, σ = [`GAUSSIAN_SIGMA_FRAMES`].
    Gaussian,
}

// The sweep (quick benchmark, RMSE mm): EMA α 0.2 / 0.3 / 0.5 → 3.35 / 2.56 / 1.98;
// One-Euro (f_min Hz, β) (0.5, 0.003) / (1, 0.01) / (2, 0.03) → 3.31 / 2.35 / 1.96; Kalman
// ratio 50 / 200 / 800 → 2.48 / 1.98 / 2.05; Gaussian σ 1 / 2 / 3 frames → 1.58 / 1.50 / 1.70.
pub const EMA_ALPHA: f64 = 0.5;
pub const ONE_EURO_MIN_CUTOFF_HZ: f64 = 2.0;
pub const ONE_EURO_BETA: f64 = 0.03;
pub const KALMAN_RATIO: f64 = 200.0;
pub const GAUSSIAN_SIGMA_FRAMES: f64 = 2.0;

impl VertexFilter {
    /// Every family, in table order.
    pub const ALL: [VertexFilter; 4] = [
        VertexFilter::Ema,
        VertexFilter::OneEuro,
        VertexFilter::Kalman,
        VertexFilter::Gaussian,
    ];

    /// Filters `solutions` (one #V × 3 field per frame, metres) vertex by vertex.
    pub fn apply(&self, solutions: &[Mat<f64>]) -> Vec<Mat<f64>> {
        let track: Vec<Vec<f64>> = solutions
            .iter()
            .map(|m| {
                (0..m.nrows())
                    .flat_map(|i| (0..3).map(move |c| 1e3 * m[(i, c)]))
                    .collect()
            })
            .collect();
        let dt = SYNTHETIC_FRAME_INTERVAL_S;
        let filtered = match self {
            VertexFilter::Ema => filter_track(&mut Ema::new(EMA_ALPHA), &track, dt),
            VertexFilter::OneEuro => filter_track(
                &mut OneEuro::new(ONE_EURO_MIN_CUTOFF_HZ, ONE_EURO_BETA),
                &track,
                dt,
            ),
            VertexFilter::Kalman => {
                let mut f: Box<dyn TrackFilter> = Box::new(ConstantVelocity::new(KALMAN_RATIO));
                filter_track(f.as_mut(), &track, dt)
            }
            VertexFilter::Gaussian => gaussian_smooth(&track, GAUSSIAN_SIGMA_FRAMES),
        };
        filtered
            .iter()
            .map(|v| Mat::from_fn(v.len() / 3, 3, |i, c| 1e-3 * v[3 * i + c]))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_still_surface_passes_and_a_flicker_is_damped() {
        let still: Vec<Mat<f64>> = (0..10)
            .map(|_| Mat::from_fn(4, 3, |i, c| (i + c) as f64))
            .collect();
        for f in VertexFilter::ALL {
            let out = f.apply(&still);
            assert!(
                (0..10).all(|t| (&out[t] - &still[t]).norm_max() < 1e-9),
                "{f:?}"
            );
        }
        let flicker: Vec<Mat<f64>> = (0..40)
            .map(|t| Mat::from_fn(2, 3, |_, _| if t % 2 == 0 { 1e-3 } else { -1e-3 }))
            .collect();
        for f in VertexFilter::ALL {
            let out = f.apply(&flicker);
            assert!(out[30][(0, 0)].abs() < 0.9e-3, "{f:?} {}", out[30][(0, 0)]);
        }
    }
}
