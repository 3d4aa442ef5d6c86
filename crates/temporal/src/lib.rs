//! Filters over time for point tracks, and the figures they are judged by.
//!
//! A *track* is one vector of scalars per frame (e.g. the 468 landmarks' `x, y`, or a mesh's
//! vertices). The causal filters ([`TrackFilter`]: [`Ema`], [`OneEuro`],
//! [`ConstantVelocity`]) see one frame at a time and answer at once, as a live tool must;
//! [`FixedLagSmoother`] answers a few frames later with those frames' help;
//! [`gaussian_smooth`] is the offline baseline that sees the whole clip. [`TrackFigures`]
//! measures a filtered track against the one it was made from: jitter (RMS second
//! difference), deviation (mean distance) and lag (the time shift that best aligns the two).
//!
//! These are the baselines a user could apply in one line; the pipeline's own temporal
//! model is judged against them (`visage eval video`).

#![forbid(unsafe_code)]

mod constant_velocity;
mod ema;
mod figures;
mod fixed_lag;
mod gaussian;
mod one_euro;

pub use constant_velocity::ConstantVelocity;
pub use ema::Ema;
pub use figures::{TrackFigures, MAX_LAG_FRAMES};
pub use fixed_lag::FixedLagSmoother;
pub use gaussian::gaussian_smooth;
pub use one_euro::OneEuro;

/// A causal filter over a track: one call per frame, the estimate for that frame back at
/// once.
pub trait TrackFilter: Send {
    /// Filters the next sample `x` (the same length every call), taken `dt` seconds after
    /// the previous one (ignored on the first call, or after [`TrackFilter::reset`]), and
    /// returns the estimate for it.
    fn step(&mut self, x: &[f64], dt: f64) -> &[f64];

    /// Forgets the history: the next sample is taken as it is (a shot cut, a lost face).
    fn reset(&mut self);
}

/// Applies a causal filter to a whole track (frames `dt` seconds apart), from a fresh state.
pub fn filter_track(filter: &mut dyn TrackFilter, track: &[Vec<f64>], dt: f64) -> Vec<Vec<f64>> {
    filter.reset();
    track.iter().map(|x| filter.step(x, dt).to_vec()).collect()
}
