//! SIFT keypoints of every frame as the fairing's confidences (paper §3: trust the data more
//! where the image shows detail). Used by [`crate::Method::FaceAnchoredFairedSift`], an
//! experiment kept out of the default method list.
//!
//! A vertex whose projection lies within [`SiftFairingOptions::radius_px`] of one of the
//! frame's keypoints keeps the full weight 1; every other vertex gets
//! [`SiftFairingOptions::base_weight`], so the fairing smooths more where the image has no
//! detail (a weight w acts as the smoothing length `ℓ w^(−1/4)`: 2.8 mm for w = 0.25 at the
//! benchmark's ℓ = 2 mm). The keypoints are those of each frame's colour render (textured with
//! [`crate::SiftAnchorOptions::textured`], the same SIFT settings as the anchors); occlusion is
//! not checked (the face-anchored mesh is the front of the face).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use visage_camera::Intrinsics;

use crate::EvalError;

/// Default [`SiftFairingOptions::base_weight`].
pub const SIFT_FAIRING_BASE_WEIGHT: f64 = 0.25;
/// Default [`SiftFairingOptions::radius_px`].
pub const SIFT_FAIRING_RADIUS_PX: f64 = 3.0;
/// Salt of the random control's seed (`mix_seed(sequence seed ^ FAIRING_CONTROL_SALT)`).
pub const FAIRING_CONTROL_SALT: u64 = 0x00fa_112e_c027;

/// The weights of [`crate::Method::FaceAnchoredFairedSift`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SiftFairingOptions {
    /// The weight of a vertex far from every keypoint, in (0, 1] (near one: 1).
    pub base_weight: f64,
    /// "Near": the projected vertex within this many pixels of a keypoint.
    pub radius_px: f64,
}

impl Default for SiftFairingOptions {
    fn default() -> Self {
        SiftFairingOptions {
            base_weight: SIFT_FAIRING_BASE_WEIGHT,
            radius_px: SIFT_FAIRING_RADIUS_PX,
        }
    }
}

impl SiftFairingOptions {
    /// Errors on a base weight outside (0, 1] or a radius that is not positive.
    pub fn validate(&self) -> Result<(), EvalError> {
        if !(self.base_weight > 0.0 && self.base_weight <= 1.0) {
            return Err(EvalError::InvalidConfig {
                name: "sift_fairing.base_weight",
                value: self.base_weight.to_string(),
                reason: "must be in (0, 1]",
            });
        }
        if !(self.radius_px.is_finite() && self.radius_px > 0.0) {
            return Err(EvalError::InvalidConfig {
                name: "sift_fairing.radius_px",
                value: self.radius_px.to_string(),
                reason: "must be positive",
            });
        }
        Ok(())
    }
}

/// What [`crate::Method::FaceAnchoredFairedSift`] is given: the keypoints of every frame and
/// how to weight.
#[derive(Clone, Copy, Debug)]
pub struct FairingKeypoints<'a> {
    /// Per frame, keypoint positions `(u, v)`, pixels.
    pub frames: &'a [Vec<[f64; 2]>],
    pub options: SiftFairingOptions,
    /// A control for the keypoints' placement: the seed of as many full-weight vertices per
    /// frame as the keypoints give, chosen uniformly at random (`None`: the keypoints'). The
    /// vertices are drawn in one random order per sequence and each frame takes its first
    /// ones, so the set is as stable over time as the keypoints' (a set drawn afresh every
    /// frame flickers, which costs jitter by itself).
    pub random_control: Option<u64>,
}

/// The per-frame fairing weights of `points` (one frame's vertices, camera coordinates)
/// projected with `k`: 1 within `options.radius_px` of one of `keypoints`, the base weight
/// elsewhere.
pub fn keypoint_weights(
    points: &[[f64; 3]],
    k: &Intrinsics,
    keypoints: &[[f64; 2]],
    options: &SiftFairingOptions,
) -> Vec<f64> {
    // Keypoints bucketed in cells of the radius: a vertex's neighbours are in its 3 × 3 cells.
    let r = options.radius_px;
    let cell = |x: f64| (x / r).floor() as i64;
    let mut grid: std::collections::HashMap<(i64, i64), Vec<[f64; 2]>> =
        std::collections::HashMap::new();
    for p in keypoints {
        grid.entry((cell(p[0]), cell(p[1]))).or_default().push(*p);
    }
    points
        .iter()
        .map(|&p| {
            let q = k.project(p);
            let (cu, cv) = (cell(q[0]), cell(q[1]));
            let near = p[2] > 0.0
                && (cu - 1..=cu + 1).any(|u| {
                    (cv - 1..=cv + 1).any(|v| {
                        grid.get(&(u, v)).is_some_and(|ks| {
                            ks.iter()
                                .any(|c| (c[0] - q[0]).powi(2) + (c[1] - q[1]).powi(2) <= r * r)
                        })
                    })
                });
            if near {
                1.0
            } else {
                options.base_weight
            }
        })
        .collect()
}

/// The random control of `weights`: as many full-weight (1) entries, at the first indices of
/// `order` (a permutation of the vertices, [`control_order`]), the others the base weight.
pub fn random_control_weights(
    weights: &[f64],
    options: &SiftFairingOptions,
    order: &[usize],
) -> Vec<f64> {
    let high = weights.iter().filter(|&&w| w >= 1.0).count();
    let mut out = vec![options.base_weight; weights.len()];
    for &i in order.iter().take(high) {
        out[i] = 1.0;
    }
    out
}

/// The random control's order of `n` vertices: a uniformly random permutation seeded by
/// `seed`.
pub fn control_order(n: usize, seed: u64) -> Vec<usize> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rand::seq::index::sample(&mut rng, n, n).into_vec()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertices_near_a_keypoint_keep_full_weight_and_the_control_as_many() {
        let k = Intrinsics {
            fx: 100.0,
            fy: 100.0,
            cx: 50.0,
            cy: 50.0,
            width: 100,
            height: 100,
        };
        // Pixels (50, 50), (52, 50), (60, 50), (50, 53.5).
        let points = [
            [0.0, 0.0, 1.0],
            [0.02, 0.0, 1.0],
            [0.1, 0.0, 1.0],
            [0.0, 0.035, 1.0],
        ];
        let options = SiftFairingOptions::default();
        let w = keypoint_weights(&points, &k, &[[50.0, 50.0]], &options);
        assert_eq!(w, [1.0, 1.0, 0.25, 0.25]);
        assert_eq!(
            keypoint_weights(&points, &k, &[], &options),
            [0.25; 4].to_vec()
        );
        let order = control_order(4, 7);
        assert_eq!(order, control_order(4, 7));
        let c = random_control_weights(&w, &options, &order);
        assert_eq!(c.iter().filter(|&&x| x == 1.0).count(), 2);
        assert_eq!((c[order[0]], c[order[1]]), (1.0, 1.0));
        assert!(SiftFairingOptions {
            base_weight: 0.0,
            ..options
        }
        .validate()
        .is_err());
        options.validate().unwrap();
    }
}
