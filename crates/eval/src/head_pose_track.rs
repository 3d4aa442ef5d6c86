//! A smooth, seeded head motion for the expression benchmark: each of yaw, pitch, roll and the
//! three translations is a sum of [`COMPONENTS`] sinusoids whose periods are incommensurate
//! (ratios of the golden mean and √2 to a base period, each scaled by a seeded factor), with
//! seeded phases, normalised to [−1, 1] and spread by a soft saturation so that a take spends
//! real time near the extremes:
//!
//! `s(t) = Σ_k w_k sin(2π t / T_k + φ_k) / Σ_k w_k`,  `a(t) = A · tanh(g s(t)) / tanh(g)`
//!
//! (g = [`SPREAD`]) — the head sweeps the whole range ±A, slowly, without ever repeating, and
//! every axis moves at once (as real heads do), which is what leaks rigid motion into
//! expression weights.
//!
//! Angles use Live Link Face's signs ([`visage_rig::live_link_rotation`]): yaw > 0 turning to
//! the subject's right, pitch > 0 looking down, roll > 0 tilting toward the right shoulder.
//! The rotation `R_head = R_y(−yaw) R_x(pitch) R_z(roll)` acts in the face frame (x to the
//! subject's left, y up, z out of the face), so the pipeline's head rotation is directly
//! comparable with it (no constant offset: both are the ICT-FaceKit face frame relative to
//! facing the camera).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::EvalError;

/// Sinusoids per axis.
pub const COMPONENTS: usize = 3;

/// The slowest component's period, seconds (before the seeded scale in [1, 1.3)).
pub const BASE_PERIOD_S: f64 = 11.0;

/// Periods of the components relative to the base: 1, 1/φ, 1/(φ√2) — no two commensurate.
const PERIOD_RATIOS: [f64; COMPONENTS] = [1.0, 0.618_033_988_749_895, 0.437_016_024_448_821];

/// The gain g of the soft saturation: a normalised sum at half its range gives 79 % of the
/// amplitude.
pub const SPREAD: f64 = 2.0;

/// Relative amplitude of the components (the slow one dominates).
const WEIGHTS: [f64; COMPONENTS] = [1.0, 0.6, 0.35];

/// Amplitudes of the head motion. Defaults: yaw ±40°, pitch ±25°, roll ±15°, ±3 cm sideways
/// and vertically, ±5 cm in depth.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct HeadMotion {
    /// Largest yaw, degrees.
    pub yaw_deg: f64,
    /// Largest pitch, degrees.
    pub pitch_deg: f64,
    /// Largest roll, degrees.
    pub roll_deg: f64,
    /// Largest translation along the camera's x and y, metres.
    pub shift_m: f64,
    /// Largest translation along the camera's z (toward or away), metres.
    pub depth_shift_m: f64,
}

impl Default for HeadMotion {
    fn default() -> Self {
        HeadMotion {
            yaw_deg: 40.0,
            pitch_deg: 25.0,
            roll_deg: 15.0,
            shift_m: 0.03,
            depth_shift_m: 0.05,
        }
    }
}

impl HeadMotion {
    /// Errors on a negative or non-finite amplitude, or angles beyond ±80° (the face would
    /// leave the view).
    pub fn validate(&self) -> Result<(), EvalError> {
        for (name, v, max) in [
            ("yaw", self.yaw_deg, 80.0),
            ("pitch", self.pitch_deg, 80.0),
            ("roll", self.roll_deg, 80.0),
            ("shift", self.shift_m, 0.2),
            ("depth-shift", self.depth_shift_m, 0.2),
        ] {
            if !(v.is_finite() && (0.0..=max).contains(&v)) {
                return Err(EvalError::InvalidConfig {
                    name,
                    value: v.to_string(),
                    reason: "must be finite, non-negative and at most 80° (0.2 m for shifts)",
                });
            }
        }
        Ok(())
    }
}

/// One frame's head pose: Live Link Face angles (radians) and the translation of the head's
/// rotation centre from its rest position (camera axes, metres).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct HeadPose {
    /// `[yaw, pitch, roll]`, radians, Live Link Face's signs.
    pub angles: [f64; 3],
    /// Camera axes (x right, y down, z forward), metres.
    pub shift_m: [f64; 3],
}

/// One axis: `COMPONENTS` (period, phase) pairs.
#[derive(Clone, Debug, PartialEq)]
struct Axis {
    periods_s: [f64; COMPONENTS],
    phases: [f64; COMPONENTS],
}

impl Axis {
    fn draw(rng: &mut ChaCha8Rng) -> Axis {
        let scale = rng.random_range(1.0..1.3);
        Axis {
            periods_s: PERIOD_RATIOS.map(|r| BASE_PERIOD_S * r * scale),
            phases: std::array::from_fn(|_| rng.random_range(0.0..std::f64::consts::TAU)),
        }
    }

    /// The value in [−1, 1] at time `t_s`: `tanh(g s(t)) / tanh(g)`.
    fn at(&self, t_s: f64) -> f64 {
        let total: f64 = WEIGHTS.iter().sum();
        let s = (0..COMPONENTS)
            .map(|k| {
                WEIGHTS[k]
                    * (std::f64::consts::TAU * t_s / self.periods_s[k] + self.phases[k]).sin()
            })
            .sum::<f64>()
            / total;
        (SPREAD * s).tanh() / SPREAD.tanh()
    }
}

/// A seeded head motion (the module's docs): build once, ask for the pose at any time.
#[derive(Clone, Debug, PartialEq)]
pub struct HeadPoseTrack {
    motion: HeadMotion,
    /// yaw, pitch, roll, x, y, z.
    axes: [Axis; 6],
}

impl HeadPoseTrack {
    /// The track of `motion` drawn from `seed`.
    ///
    /// # Errors
    /// An invalid `motion` ([`HeadMotion::validate`]).
    pub fn new(motion: HeadMotion, seed: u64) -> Result<HeadPoseTrack, EvalError> {
        motion.validate()?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        Ok(HeadPoseTrack {
            motion,
            axes: std::array::from_fn(|_| Axis::draw(&mut rng)),
        })
    }

    /// The pose at `t_s` seconds from the take's start.
    pub fn at(&self, t_s: f64) -> HeadPose {
        let m = &self.motion;
        let v = |i: usize| self.axes[i].at(t_s);
        HeadPose {
            angles: [
                (m.yaw_deg * v(0)).to_radians(),
                (m.pitch_deg * v(1)).to_radians(),
                (m.roll_deg * v(2)).to_radians(),
            ],
            shift_m: [m.shift_m * v(3), m.shift_m * v(4), m.depth_shift_m * v(5)],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_track_is_smooth_seeded_and_sweeps_its_range() {
        let motion = HeadMotion::default();
        let track = HeadPoseTrack::new(motion, 7).unwrap();
        assert_eq!(track, HeadPoseTrack::new(motion, 7).unwrap());
        assert_ne!(track, HeadPoseTrack::new(motion, 8).unwrap());
        let dt = 1.0 / 30.0;
        let poses: Vec<HeadPose> = (0..30 * 300).map(|i| track.at(i as f64 * dt)).collect();
        for (axis, amplitude) in [motion.yaw_deg, motion.pitch_deg, motion.roll_deg]
            .into_iter()
            .enumerate()
        {
            let deg: Vec<f64> = poses.iter().map(|p| p.angles[axis].to_degrees()).collect();
            let (lo, hi) = deg
                .iter()
                .fold((f64::MAX, f64::MIN), |(l, h), &d| (l.min(d), h.max(d)));
            // Within the amplitude, and five minutes reach most of it on both sides.
            assert!(
                hi <= amplitude + 1e-9 && lo >= -amplitude - 1e-9,
                "{axis}: {lo} {hi}"
            );
            assert!(
                hi > 0.9 * amplitude && lo < -0.9 * amplitude,
                "{axis}: {lo} {hi}"
            );
            // Smooth: a frame's step stays below the components' peak rate (times the
            // saturation's largest slope, g / tanh g).
            let peak_rate: f64 = (0..COMPONENTS)
                .map(|k| WEIGHTS[k] * std::f64::consts::TAU / (BASE_PERIOD_S * PERIOD_RATIOS[k]))
                .sum::<f64>()
                / WEIGHTS.iter().sum::<f64>()
                * SPREAD
                / SPREAD.tanh()
                * amplitude;
            let step = deg
                .windows(2)
                .map(|w| (w[1] - w[0]).abs())
                .fold(0.0, f64::max);
            assert!(step <= peak_rate * dt + 1e-9, "{axis}: step {step}");
        }
        for p in &poses {
            assert!(p.shift_m[0].abs() <= motion.shift_m + 1e-12);
            assert!(p.shift_m[2].abs() <= motion.depth_shift_m + 1e-12);
        }
        // The axes are not locked to each other: yaw and pitch are not proportional.
        let angle = |i: usize| poses.iter().map(|p| p.angles[i] as f32).collect::<Vec<_>>();
        let r = crate::expression_scores::pearson(&angle(0), &angle(1)).unwrap();
        assert!(r.abs() < 0.5, "yaw–pitch correlation {r}");
    }

    #[test]
    fn a_still_head_and_bad_amplitudes() {
        let still = HeadMotion {
            yaw_deg: 0.0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            shift_m: 0.0,
            depth_shift_m: 0.0,
        };
        let p = HeadPoseTrack::new(still, 1).unwrap().at(3.7);
        assert_eq!(p.angles, [0.0; 3]);
        assert_eq!(p.shift_m, [0.0; 3]);
        for bad in [-1.0, f64::NAN, 95.0] {
            let m = HeadMotion {
                yaw_deg: bad,
                ..HeadMotion::default()
            };
            assert!(HeadPoseTrack::new(m, 1).is_err(), "{bad}");
        }
    }
}
