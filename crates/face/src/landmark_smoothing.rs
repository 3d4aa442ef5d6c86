//! The pipeline's temporal model of the tracked face: a constant-velocity Kalman filter on
//! the landmark network's 468 points (`x, y` in frame pixels and the relative `z`), between
//! the tracker and everything that uses the landmarks (the metric fit, the model fit, the
//! eyes, the fusion).
//!
//! Why here and why this filter (docs/performance.md, "Temporal stability"): the landmark
//! network's noise lies inside the face's own deformation space, so no per-frame shape prior
//! removes it, and on the shared clips every causal filter tried — EMA, One-Euro, per-mode
//! Kalman on the pose and a shape basis, pooled-speed variants — lands on the same jitter
//! against deviation curve; the constant-velocity model is on it with the least lag for a
//! given smoothing (it follows a steady motion exactly). Filtering the points once, before
//! the fit, makes the pose, the blendshapes and the surface steady together. The tracker
//! itself keeps the raw points, so its crop does not lag the face.

use crate::FaceGeometry;
use visage_temporal::{ConstantVelocity, FixedLagSmoother, TrackFilter};

/// Frame interval assumed when the input has neither timestamps nor a frame rate (images).
pub const DEFAULT_FRAME_INTERVAL_S: f64 = 1.0 / 30.0;

/// Default acceleration-to-noise ratio of the landmark filter (1/s²): measured on the shared
/// clips with `visage eval video` (docs/performance.md).
pub const DEFAULT_LANDMARK_SMOOTHING: f64 = 1500.0;

/// Default latency of the landmark smoother in streaming mode, frames.
pub const DEFAULT_LATENCY_FRAMES: usize = 1;

/// The longest latency allowed, frames (the frames waiting are held in memory, images too).
pub const MAX_LATENCY_FRAMES: usize = 30;

/// The landmark smoother's latency in clip mode, frames: long enough that the estimate is the
/// whole track's (the smoother's gains on frames further ahead are below 1 %), short enough
/// that the frames held back stay few.
pub const CLIP_LATENCY_FRAMES: usize = 8;

/// The time of a filter's last frame.
#[derive(Default)]
struct FrameClock {
    last_s: Option<f64>,
}

impl FrameClock {
    /// The interval from the last frame to the frame at `time_s` (seconds; `None`, or a time
    /// not after the last: one default interval): 0 on the first frame.
    fn step(&mut self, time_s: Option<f64>) -> f64 {
        let dt = match (time_s, self.last_s) {
            (Some(t), Some(last)) if t > last => t - last,
            (_, Some(_)) => DEFAULT_FRAME_INTERVAL_S,
            (_, None) => 0.0,
        };
        self.last_s = Some(match (time_s, self.last_s) {
            (Some(t), _) => t,
            (None, last) => last.map_or(0.0, |l| l + dt),
        });
        dt
    }
}

/// The landmark smoother and the time of its last frame.
pub struct LandmarkSmoother {
    smoother: FixedLagSmoother,
    clock: FrameClock,
    scratch: Vec<f64>,
}

fn to_points(v: &[f64]) -> Vec<[f32; 3]> {
    v.chunks_exact(3)
        .map(|q| [q[0] as f32, q[1] as f32, q[2] as f32])
        .collect()
}

impl LandmarkSmoother {
    pub fn new(accel_ratio: f64, latency: usize) -> Self {
        LandmarkSmoother {
            smoother: FixedLagSmoother::new(accel_ratio, latency),
            clock: FrameClock::default(),
            scratch: Vec::new(),
        }
    }

    /// Drops the latency (before the first frame, or between tracks).
    pub fn make_causal(&mut self) {
        if self.smoother.lag() > 0 && self.smoother.waiting() == 0 {
            self.smoother = FixedLagSmoother::new(self.smoother.accel_ratio(), 0);
        }
    }

    /// Takes the landmarks of the frame at `time_s` (seconds; `None`: one default interval
    /// after the last); returns the smoothed landmarks of the frame `latency` frames back,
    /// once there is one.
    pub fn push(&mut self, points: &[[f32; 3]], time_s: Option<f64>) -> Option<Vec<[f32; 3]>> {
        let dt = self.clock.step(time_s);
        self.scratch.clear();
        self.scratch
            .extend(points.iter().flat_map(|p| p.map(f64::from)));
        self.smoother.push(&self.scratch, dt).map(|v| to_points(&v))
    }

    /// The smoothed landmarks of the frames not given out yet, oldest first; then starts
    /// afresh (a cut, a lost face, the end).
    pub fn finish(&mut self) -> Vec<Vec<[f32; 3]>> {
        self.clock = FrameClock::default();
        self.smoother
            .finish()
            .iter()
            .map(|v| to_points(v))
            .collect()
    }
}

/// Default acceleration-to-noise ratio of the head's distance filter (1/s²).
pub const DEFAULT_DISTANCE_SMOOTHING: f64 = 30.0;

/// The head's distance from the camera, filtered apart from everything else. A face's
/// distance is seen only through its size in the image, the noisiest thing the landmarks
/// give, while scaling the fitted face about the camera centre leaves every projection where
/// it was: a slow causal filter on the distance steadies the metric surface without moving
/// it in the image.
pub struct DistanceSmoother {
    filter: ConstantVelocity,
    clock: FrameClock,
}

impl DistanceSmoother {
    pub fn new(accel_ratio: f64) -> Self {
        DistanceSmoother {
            filter: ConstantVelocity::new(accel_ratio),
            clock: FrameClock::default(),
        }
    }

    /// Scales the fit about the camera centre to the filtered distance of the frame at
    /// `time_s`.
    pub fn smooth(&mut self, geometry: &mut FaceGeometry, time_s: Option<f64>) {
        let dt = self.clock.step(time_s);
        let z = geometry.pose.translation[2];
        let filtered = self.filter.step(&[z], dt)[0];
        if !(z > 0.0 && filtered > 0.0) {
            return;
        }
        let s = filtered / z;
        geometry.pose.translation = geometry.pose.translation.map(|c| c * s);
        for p in geometry
            .fitted_vertices
            .iter_mut()
            .chain(&mut geometry.metric_landmarks)
        {
            *p = p.map(|c| c * s);
        }
    }

    /// Starts afresh (a cut, a lost face).
    pub fn reset(&mut self) {
        self.filter.reset();
        self.clock = FrameClock::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_come_out_after_the_latency_and_a_finish_restarts() {
        let mut s = LandmarkSmoother::new(100.0, 1);
        let a = vec![[1.0f32, 2.0, 3.0]; 4];
        assert!(s.push(&a, Some(0.0)).is_none());
        let b = vec![[5.0f32, 5.0, 5.0]; 4];
        let first = s.push(&b, Some(0.04)).unwrap();
        // The first frame, pulled towards the second by the smoother.
        assert!(first[0][0] > 1.0 && first[0][0] < 5.0, "{:?}", first[0]);
        let rest = s.finish();
        assert_eq!(rest.len(), 1);
        let c = vec![[9.0f32, 9.0, 9.0]; 4];
        assert!(s.push(&c, Some(0.08)).is_none());
        assert_eq!(s.finish(), vec![c]);
    }
}
