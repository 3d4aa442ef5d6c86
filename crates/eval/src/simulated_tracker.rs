//! A simulated face tracker for the benchmark: what the face-anchored fusion gets
//! from FaceMesh on real video, derived from the ground truth with a documented noise model.
//!
//! Per frame k and landmark i (the 468 canonical vertices, placed on the ICT face by the
//! [`CanonicalCorrespondence`]), with `X_k(i)` the true camera-space point and `π` the
//! pinhole projection (Eq. 2.1):
//! - **pixels**: `π(X_k(i)) + w_k(i) + c_k(i)`, with white noise `w ~ N(0, white_px² I)`
//!   independent per landmark, axis and frame (the frame-to-frame jitter of a landmark network),
//!   and a temporally correlated part `c_k = ρ c_{k−1} + √(1−ρ²) n_k`, `n_k ~ N(0,
//!   correlated_px² I)`, stationary from `c_0 ~ N(0, correlated_px² I)` (slow drift of the
//!   landmarks over the skin);
//! - **relative depth** as FaceMesh reports it: `(z_k(i) − z̄_k) f / z̄_k` pixels, `z̄_k` the mean
//!   z of the 468 points, plus white noise of σ `white_px`;
//! - **temporal model** (optional, as `visage run` does by default): the landmarks and their
//!   relative depth through the constant-velocity Kalman smoother with one frame of latency;
//! - **head pose** `T_k`: [`visage_face::fit_face_geometry`] on the (smoothed) noisy
//!   landmarks — exactly what `visage run` does on real video (so pose errors and the
//!   canonical face's size mismatch with the synthetic identity are part of the test).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use visage_camera::RigidTransform;
use visage_face::{fit_face_geometry, CanonicalMesh};

use visage_face::DEFAULT_LATENCY_FRAMES;
use visage_temporal::FixedLagSmoother;

use crate::normal::standard_normal;
use crate::synthesis::SyntheticSequence;
use crate::vertex_filter::SYNTHETIC_FRAME_INTERVAL_S;
use crate::EvalError;
use visage_morphable::CanonicalCorrespondence;

/// The tracker's noise (module docs). Default: 0.5 px white, 0.3 px correlated with ρ = 0.9
/// (a correlation time of ~10 frames).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct TrackerNoise {
    /// σ of the white landmark noise per axis, pixels.
    pub white_px: f64,
    /// Stationary σ of the correlated landmark noise per axis, pixels.
    pub correlated_px: f64,
    /// AR(1) coefficient ρ of the correlated noise from frame to frame, in [0, 1).
    pub correlation: f64,
}

impl Default for TrackerNoise {
    fn default() -> Self {
        TrackerNoise {
            white_px: 0.5,
            correlated_px: 0.3,
            correlation: 0.9,
        }
    }
}

impl TrackerNoise {
    /// Errors on values outside their documented ranges.
    pub fn validate(&self) -> Result<(), EvalError> {
        let ok = |v: f64| v.is_finite() && v >= 0.0;
        if !(ok(self.white_px) && ok(self.correlated_px)) {
            return Err(EvalError::InvalidConfig {
                name: "tracker noise",
                value: format!("{} / {} px", self.white_px, self.correlated_px),
                reason: "must be finite and non-negative",
            });
        }
        if !(0.0..1.0).contains(&self.correlation) {
            return Err(EvalError::InvalidConfig {
                name: "tracker correlation",
                value: self.correlation.to_string(),
                reason: "must lie in [0, 1)",
            });
        }
        Ok(())
    }
}

/// What the simulated tracker reports for a sequence, and the truth behind it.
#[derive(Clone, Debug)]
pub struct TrackedSequence {
    /// Per frame: the 468 noisy landmark pixels.
    pub landmarks_px: Vec<Vec<[f64; 2]>>,
    /// Per frame: the head pose fitted to the noisy landmarks (canonical → camera).
    pub poses: Vec<RigidTransform>,
    /// Per frame: the true camera-space position of each canonical vertex, metres.
    pub truth: Vec<Vec<[f64; 3]>>,
}

/// Tracks `seq` with `noise`, deterministically from `seed`; with `smoothing` (the
/// smoother's acceleration-to-noise ratio, 1/s²) the landmarks go through the pipeline's
/// temporal model before the fit.
///
/// # Errors
/// When the metric face fit fails on a frame (degenerate landmarks).
pub fn simulate_tracking(
    seq: &SyntheticSequence,
    correspondence: &CanonicalCorrespondence,
    canonical: &CanonicalMesh,
    noise: &TrackerNoise,
    smoothing: Option<f64>,
    seed: u64,
) -> Result<TrackedSequence, EvalError> {
    noise.validate()?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let m = correspondence.points.len();
    let rho = noise.correlation;
    let innovation = (1.0 - rho * rho).sqrt() * noise.correlated_px;
    let mut drift: Vec<[f64; 2]> = (0..m)
        .map(|_| std::array::from_fn(|_| noise.correlated_px * standard_normal(&mut rng)))
        .collect();
    let mut out = TrackedSequence {
        landmarks_px: Vec::with_capacity(seq.frames.len()),
        poses: Vec::with_capacity(seq.frames.len()),
        truth: Vec::with_capacity(seq.frames.len()),
    };
    let f = seq.k.focal();
    // Per frame: x, y (pixels) and relative z of every landmark.
    let mut tracked: Vec<Vec<f64>> = Vec::with_capacity(seq.frames.len());
    for (index, frame) in seq.frames.iter().enumerate() {
        let mut truth = vec![[0.0; 3]; m];
        correspondence.place(&frame.vertices, &mut truth);
        if index > 0 {
            for d in &mut drift {
                *d = d.map(|c| rho * c + innovation * standard_normal(&mut rng));
            }
        }
        let z_mean = truth.iter().map(|p| p[2]).sum::<f64>() / m as f64;
        let mut points = Vec::with_capacity(3 * m);
        for (x, d) in truth.iter().zip(&drift) {
            let p = seq.k.project(*x);
            let px: [f64; 2] =
                std::array::from_fn(|a| p[a] + d[a] + noise.white_px * standard_normal(&mut rng));
            let z = (x[2] - z_mean) * f / z_mean + noise.white_px * standard_normal(&mut rng);
            points.extend([px[0], px[1], z]);
        }
        tracked.push(points);
        out.truth.push(truth);
    }
    if let Some(ratio) = smoothing {
        let mut smoother = FixedLagSmoother::new(ratio, DEFAULT_LATENCY_FRAMES);
        let mut smoothed: Vec<Vec<f64>> = tracked
            .iter()
            .filter_map(|x| smoother.push(x, SYNTHETIC_FRAME_INTERVAL_S))
            .collect();
        smoothed.extend(smoother.finish());
        tracked = smoothed;
    }
    for (index, frame) in tracked.iter().enumerate() {
        let points: Vec<[f32; 3]> = frame
            .chunks_exact(3)
            .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32])
            .collect();
        let fit =
            fit_face_geometry(canonical, &points, &seq.k).map_err(|e| EvalError::Degenerate {
                seed: seq.seed,
                reason: format!("frame {index}: metric face fit: {e}"),
            })?;
        out.landmarks_px
            .push(frame.chunks_exact(3).map(|p| [p[0], p[1]]).collect());
        out.poses.push(fit.pose);
    }
    Ok(out)
}
