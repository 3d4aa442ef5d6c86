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
//! - **head pose** `T_k`: [`visage_face::fit_face_geometry`] on the noisy landmarks — exactly
//!   what `visage run` does on real video (so pose errors and the canonical face's size
//!   mismatch with the synthetic identity are part of the test).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use visage_camera::RigidTransform;
use visage_face::{fit_face_geometry, CanonicalMesh};

use crate::normal::standard_normal;
use crate::synthesis::SyntheticSequence;
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

/// Tracks `seq` with `noise`, deterministically from `seed`.
///
/// # Errors
/// When the metric face fit fails on a frame (degenerate landmarks).
pub fn simulate_tracking(
    seq: &SyntheticSequence,
    correspondence: &CanonicalCorrespondence,
    canonical: &CanonicalMesh,
    noise: &TrackerNoise,
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
    for (index, frame) in seq.frames.iter().enumerate() {
        let mut truth = vec![[0.0; 3]; m];
        correspondence.place(&frame.vertices, &mut truth);
        if index > 0 {
            for d in &mut drift {
                *d = d.map(|c| rho * c + innovation * standard_normal(&mut rng));
            }
        }
        let z_mean = truth.iter().map(|p| p[2]).sum::<f64>() / m as f64;
        let mut landmarks = Vec::with_capacity(m);
        let mut points = Vec::with_capacity(m);
        for (x, d) in truth.iter().zip(&drift) {
            let p = seq.k.project(*x);
            let px: [f64; 2] =
                std::array::from_fn(|a| p[a] + d[a] + noise.white_px * standard_normal(&mut rng));
            let z = (x[2] - z_mean) * f / z_mean + noise.white_px * standard_normal(&mut rng);
            landmarks.push(px);
            points.push([px[0] as f32, px[1] as f32, z as f32]);
        }
        let fit =
            fit_face_geometry(canonical, &points, &seq.k).map_err(|e| EvalError::Degenerate {
                seed: seq.seed,
                reason: format!("frame {index}: metric face fit: {e}"),
            })?;
        out.landmarks_px.push(landmarks);
        out.poses.push(fit.pose);
        out.truth.push(truth);
    }
    Ok(out)
}
