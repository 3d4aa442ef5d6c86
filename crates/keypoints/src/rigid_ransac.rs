//! A rigid motion from 3-D point correspondences with gross outliers, by RANSAC (Fischler &
//! Bolles, CACM 1981): an estimate of the head's motion between two frames from matched
//! keypoints lifted to 3-D, independent of any face model.
//!
//! Each iteration draws a minimal sample of three pairs, fits the motion to it in closed form
//! ([`RigidTransform::fit`], Horn 1987) and counts the pairs it maps within the inlier
//! threshold. The number of iterations adapts to the best inlier fraction `w` found so far:
//! `N = log(1 − p) / log(1 − w³)` for the confidence `p` (Hartley & Zisserman 2004, §4.7.1).
//! The best consensus set is then refitted by least squares and re-classified a few times.
//!
//! Samples that cannot determine a motion or cannot be all inliers are skipped (they still
//! count as iterations): three points nearly collinear or too close together, and triples
//! whose pairwise distances differ between source and target by more than twice the
//! threshold (a rigid motion keeps distances, so two pairs whose distances differ by more than
//! `2 τ` cannot both lie within `τ` of any rigid motion).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use visage_camera::vec3::{cross, distance, distance2, norm, sub};
use visage_camera::RigidTransform;

/// 4 mm: meant as a few times the 3-D noise of keypoints lifted at face distance (~0.5 m);
/// not yet tuned on recordings.
const DEFAULT_INLIER_THRESHOLD: f64 = 0.004;
/// With 3-point samples this suffices for inlier fractions down to ~24 % at 99.9 %
/// confidence (`log(0.001) / log(1 − 0.24³) ≈ 500`).
const DEFAULT_MAX_ITERATIONS: usize = 500;
/// Probability that at least one sample is outlier-free when the adaptive count stops.
const DEFAULT_CONFIDENCE: f64 = 0.999;
/// Fewer inliers than this and no motion is reported: three pairs always fit exactly, and a
/// few more are needed before the consensus says anything.
const DEFAULT_MIN_INLIERS: usize = 6;
/// Default seed of the sampler.
const DEFAULT_SEED: u64 = 0;

/// Pairs per minimal sample: three non-collinear points determine a rigid motion.
const SAMPLE_SIZE: usize = 3;
/// A sample's triangle must have every height (hence every side) at least this many inlier
/// thresholds, in source and in target: a rotation fitted to points closer together than a
/// few noise levels is mostly noise.
const MIN_SAMPLE_HEIGHT_IN_THRESHOLDS: f64 = 3.0;
/// Pairwise distances of a sample may differ between source and target by at most this many
/// inlier thresholds (2 is the bound that can never reject an all-inlier sample).
const MAX_DISTANCE_CHANGE_IN_THRESHOLDS: f64 = 2.0;
/// Least-squares refits of the consensus set, each followed by re-classifying every pair.
const REFINEMENTS: usize = 3;

/// How to run [`estimate_rigid_motion`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RansacOptions {
    /// A pair `(a, b)` is an inlier of a motion `T` when `‖T a − b‖ < inlier_threshold`,
    /// metres (default 0.004). Must be finite and positive, else nothing is estimated.
    pub inlier_threshold: f64,
    /// Samples drawn at most, degenerate ones included (default 500).
    pub max_iterations: usize,
    /// Stop once the probability of having drawn at least one all-inlier sample, given the
    /// best inlier fraction so far, reaches this (default 0.999; 1 or more: always
    /// `max_iterations`; 0 or less: stop at the first hypothesis).
    pub confidence: f64,
    /// Fewest inliers for an estimate (default 6; below 3 counts as 3).
    pub min_inliers: usize,
    /// Seed of the sampler (ChaCha8): equal inputs and options give equal results.
    pub seed: u64,
}

impl Default for RansacOptions {
    /// 4 mm, 500 iterations, 99.9 % confidence, 6 inliers, seed 0.
    fn default() -> Self {
        RansacOptions {
            inlier_threshold: DEFAULT_INLIER_THRESHOLD,
            max_iterations: DEFAULT_MAX_ITERATIONS,
            confidence: DEFAULT_CONFIDENCE,
            min_inliers: DEFAULT_MIN_INLIERS,
            seed: DEFAULT_SEED,
        }
    }
}

/// A rigid motion estimated by [`estimate_rigid_motion`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RigidMotionEstimate {
    /// Maps source points onto target points: `target ≈ R · source + t` (t in metres); the
    /// least-squares fit ([`RigidTransform::fit`], unit weights) over [`Self::inliers`].
    pub transform: RigidTransform,
    /// Indices of the inlier pairs into the input slices, ascending. They were classified by
    /// the previous refit, so a few may lie marginally beyond the threshold of `transform`.
    pub inliers: Vec<usize>,
    /// Root-mean-square of `‖T a − b‖` over the inliers, metres.
    pub rms: f64,
}

/// The rigid motion `T` with `target[i] ≈ T source[i]` for as many pairs `i` as possible, by
/// RANSAC (Fischler & Bolles 1981) with 3-point samples and an adaptive iteration count, the
/// best consensus then refitted by least squares ([`RigidTransform::fit`]).
///
/// Points are in metres. Pairs with a non-finite coordinate are never sampled nor inliers.
/// Deterministic for a given [`RansacOptions::seed`].
///
/// Returns `None` when `source` and `target` differ in length, when the threshold is not
/// finite and positive, or when no motion gathers [`RansacOptions::min_inliers`] inliers (too
/// few pairs, too many outliers, or degenerate geometry such as collinear points).
pub fn estimate_rigid_motion(
    source: &[[f64; 3]],
    target: &[[f64; 3]],
    options: &RansacOptions,
) -> Option<RigidMotionEstimate> {
    let threshold = options.inlier_threshold;
    if source.len() != target.len() || !(threshold > 0.0 && threshold.is_finite()) {
        return None;
    }
    let min_inliers = options.min_inliers.max(SAMPLE_SIZE);
    let usable: Vec<usize> = (0..source.len())
        .filter(|&i| source[i].iter().chain(&target[i]).all(|v| v.is_finite()))
        .collect();
    if usable.len() < min_inliers {
        return None;
    }
    let pairs = Pairs {
        source,
        target,
        usable: &usable,
        threshold_sq: threshold * threshold,
    };

    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut best: Vec<usize> = Vec::new();
    let mut best_cost = f64::INFINITY;
    let mut candidate = Vec::with_capacity(usable.len());
    let mut required = options.max_iterations;
    let mut drawn = 0;
    while drawn < required {
        drawn += 1;
        let sample = draw_sample(&mut rng, usable.len()).map(|k| usable[k]);
        if !is_usable_sample(source, target, sample, threshold) {
            continue;
        }
        let Some(hypothesis) = fit(source, target, &sample) else {
            continue;
        };
        let cost = pairs.consensus(&hypothesis, &mut candidate);
        if candidate.len() > best.len() || (candidate.len() == best.len() && cost < best_cost) {
            std::mem::swap(&mut best, &mut candidate);
            best_cost = cost;
            let fraction = best.len() as f64 / usable.len() as f64;
            required = required_iterations(fraction, options.confidence, options.max_iterations);
        }
    }
    if best.len() < min_inliers {
        return None;
    }

    let mut inliers = best;
    for _ in 0..REFINEMENTS {
        let refit = fit(source, target, &inliers)?;
        pairs.consensus(&refit, &mut candidate);
        if candidate == inliers || candidate.len() < min_inliers {
            break;
        }
        std::mem::swap(&mut inliers, &mut candidate);
    }
    let transform = fit(source, target, &inliers)?;
    let sum_sq: f64 = inliers
        .iter()
        .map(|&i| squared_residual(&transform, source[i], target[i]))
        .sum();
    let rms = (sum_sq / inliers.len() as f64).sqrt();
    Some(RigidMotionEstimate {
        transform,
        inliers,
        rms,
    })
}

/// The correspondences and what counts as an inlier.
struct Pairs<'a> {
    source: &'a [[f64; 3]],
    target: &'a [[f64; 3]],
    /// Indices of the pairs with finite coordinates.
    usable: &'a [usize],
    /// Squared inlier threshold, m².
    threshold_sq: f64,
}

impl Pairs<'_> {
    /// Fills `inliers` (ascending) with the usable pairs `T` maps within the threshold and
    /// returns the sum of their squared residuals, m² (the tie-break between equal counts).
    fn consensus(&self, t: &RigidTransform, inliers: &mut Vec<usize>) -> f64 {
        inliers.clear();
        let mut cost = 0.0;
        for &i in self.usable {
            let r = squared_residual(t, self.source[i], self.target[i]);
            if r < self.threshold_sq {
                inliers.push(i);
                cost += r;
            }
        }
        cost
    }
}

/// `‖T a − b‖²`.
fn squared_residual(t: &RigidTransform, a: [f64; 3], b: [f64; 3]) -> f64 {
    distance2(t.apply(a), b)
}

/// The least-squares motion of the pairs `indices` (unit weights), if finite.
fn fit(source: &[[f64; 3]], target: &[[f64; 3]], indices: &[usize]) -> Option<RigidTransform> {
    RigidTransform::fit(indices.iter().map(|&i| (source[i], target[i], 1.0)))
        .filter(RigidTransform::is_finite)
}

/// Three distinct indices in `0..n` (`n ≥ 3`), uniformly.
fn draw_sample(rng: &mut ChaCha8Rng, n: usize) -> [usize; SAMPLE_SIZE] {
    let i = rng.random_range(0..n);
    let mut j = rng.random_range(0..n - 1);
    if j >= i {
        j += 1;
    }
    let (lo, hi) = (i.min(j), i.max(j));
    let mut k = rng.random_range(0..n - 2);
    if k >= lo {
        k += 1;
    }
    if k >= hi {
        k += 1;
    }
    [i, j, k]
}

/// Whether a sample can determine a motion (a well-shaped triangle in source and target) and
/// could be all inliers (pairwise distances kept within `2 τ`).
fn is_usable_sample(
    source: &[[f64; 3]],
    target: &[[f64; 3]],
    sample: [usize; SAMPLE_SIZE],
    threshold: f64,
) -> bool {
    let a = sample.map(|i| source[i]);
    let b = sample.map(|i| target[i]);
    let min_height = MIN_SAMPLE_HEIGHT_IN_THRESHOLDS * threshold;
    let max_change = MAX_DISTANCE_CHANGE_IN_THRESHOLDS * threshold;
    let keeps_distances = [(0, 1), (0, 2), (1, 2)]
        .iter()
        .all(|&(i, j)| (distance(a[i], a[j]) - distance(b[i], b[j])).abs() <= max_change);
    keeps_distances && is_well_shaped(a, min_height) && is_well_shaped(b, min_height)
}

/// Whether every height of the triangle `p` is at least `min_height` (its smallest height is
/// twice its area over its longest side).
fn is_well_shaped(p: [[f64; 3]; 3], min_height: f64) -> bool {
    let u = sub(p[1], p[0]);
    let v = sub(p[2], p[0]);
    let twice_area = norm(cross(u, v));
    let longest = distance(p[0], p[1])
        .max(distance(p[0], p[2]))
        .max(distance(p[1], p[2]));
    longest > 0.0 && twice_area >= min_height * longest
}

/// Samples needed so that, with an inlier fraction `inlier_fraction`, at least one is all
/// inliers with probability `confidence`: `log(1 − p) / log(1 − w³)`, at most `max`.
fn required_iterations(inlier_fraction: f64, confidence: f64, max: usize) -> usize {
    let all_inliers = inlier_fraction.powi(SAMPLE_SIZE as i32);
    if all_inliers >= 1.0 || confidence <= 0.0 {
        return 0;
    }
    if confidence.is_nan() || confidence >= 1.0 || all_inliers.is_nan() || all_inliers <= 0.0 {
        return max;
    }
    let needed = (-confidence).ln_1p() / (-all_inliers).ln_1p();
    if needed.is_finite() && needed < max as f64 {
        // Finite, non-negative and below `max`: the conversion is exact after `ceil`.
        needed.ceil() as usize
    } else {
        max
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::seq::SliceRandom;

    /// Half-width of the face-sized box the test points fill, metres.
    const HALF_BOX: f64 = 0.08;
    /// Depth of the box's centre, metres.
    const DEPTH: f64 = 0.5;

    fn random_point(rng: &mut ChaCha8Rng) -> [f64; 3] {
        [
            rng.random_range(-HALF_BOX..HALF_BOX),
            rng.random_range(-HALF_BOX..HALF_BOX),
            DEPTH + rng.random_range(-HALF_BOX..HALF_BOX),
        ]
    }

    /// A standard normal sample (Box–Muller).
    fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
        let u: f64 = rng.random_range(f64::EPSILON..1.0);
        let v: f64 = rng.random();
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }

    /// The rotation by `angle` radians about `axis` (Rodrigues).
    fn axis_angle(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
        let n = norm(axis);
        let [x, y, z] = axis.map(|v| v / n);
        let (s, c) = angle.sin_cos();
        let k = 1.0 - c;
        [
            [c + x * x * k, x * y * k - z * s, x * z * k + y * s],
            [y * x * k + z * s, c + y * y * k, y * z * k - x * s],
            [z * x * k - y * s, z * y * k + x * s, c + z * z * k],
        ]
    }

    /// The angle of `M = R₁ R₂ᵀ`, degrees: `atan2(‖vee(M − Mᵀ)‖ / 2, (tr M − 1) / 2)`, accurate
    /// near 0 where `acos` is not.
    fn rotation_error_degrees(r1: &[[f64; 3]; 3], r2: &[[f64; 3]; 3]) -> f64 {
        let m: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| r1[i][k] * r2[j][k]).sum())
        });
        let skew = [m[2][1] - m[1][2], m[0][2] - m[2][0], m[1][0] - m[0][1]];
        let trace = m[0][0] + m[1][1] + m[2][2];
        (0.5 * norm(skew)).atan2(0.5 * (trace - 1.0)).to_degrees()
    }

    fn true_motion() -> RigidTransform {
        RigidTransform {
            rotation: axis_angle([0.3, 1.0, 0.2], 5f64.to_radians()),
            translation: [0.012, -0.006, 0.02],
        }
    }

    /// `n` pairs under `motion` with Gaussian noise of `sigma` metres per axis, the pairs in
    /// `outliers` replaced by unrelated target points.
    fn pairs(
        rng: &mut ChaCha8Rng,
        n: usize,
        motion: &RigidTransform,
        sigma: f64,
        outliers: &[usize],
    ) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let source: Vec<[f64; 3]> = (0..n).map(|_| random_point(rng)).collect();
        let mut target: Vec<[f64; 3]> = source
            .iter()
            .map(|&a| motion.apply(a).map(|v| v + sigma * gaussian(rng)))
            .collect();
        for &i in outliers {
            target[i] = motion.apply(random_point(rng));
        }
        (source, target)
    }

    #[test]
    fn recovers_a_head_motion_among_forty_percent_outliers() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let n = 200;
        let mut order: Vec<usize> = (0..n).collect();
        order.shuffle(&mut rng);
        let mut outliers = order[..n * 2 / 5].to_vec();
        outliers.sort_unstable();
        let motion = true_motion();
        let (source, target) = pairs(&mut rng, n, &motion, 0.001, &outliers);

        let estimate = estimate_rigid_motion(&source, &target, &RansacOptions::default());
        let Some(estimate) = estimate else {
            panic!("no estimate");
        };
        // With 1 mm noise on 120 inliers the least-squares rotation itself is off by ~0.1°
        // (here 0.27°), and that error, levered by the 0.5 m from the camera to the face,
        // moves `t` by millimetres: the translation is checked where the face is.
        let rotation_error = rotation_error_degrees(&estimate.transform.rotation, &motion.rotation);
        assert!(rotation_error < 0.3, "rotation error {rotation_error}°");
        let centre = [0.0, 0.0, DEPTH];
        let translation_error = distance(estimate.transform.apply(centre), motion.apply(centre));
        assert!(
            translation_error < 0.002,
            "error of the face centre's motion {translation_error} m"
        );

        // RANSAC's own part: the same motion as least squares on the true inliers.
        let true_inliers: Vec<usize> = (0..n).filter(|i| !outliers.contains(i)).collect();
        let Some(oracle) = fit(&source, &target, &true_inliers) else {
            panic!("no least-squares fit");
        };
        let from_oracle = rotation_error_degrees(&estimate.transform.rotation, &oracle.rotation);
        assert!(from_oracle < 0.02, "{from_oracle}° from the oracle");
        let from_oracle = distance(estimate.transform.translation, oracle.translation);
        assert!(from_oracle < 2e-4, "{from_oracle} m from the oracle");

        let found = estimate
            .inliers
            .iter()
            .filter(|i| true_inliers.contains(i))
            .count();
        let false_inliers = estimate.inliers.len() - found;
        assert!(
            found * 100 >= true_inliers.len() * 97,
            "{found} of {} inliers",
            true_inliers.len()
        );
        assert!(false_inliers <= 2, "{false_inliers} outliers taken in");
        assert!(estimate.inliers.windows(2).all(|w| w[0] < w[1]));
        // 1 mm per axis: ‖noise‖ has rms √3 mm, a little less once the tail is cut at 4 mm.
        assert!(
            (0.001..0.0025).contains(&estimate.rms),
            "rms {} m",
            estimate.rms
        );
    }

    #[test]
    fn exact_correspondences_are_fitted_exactly() {
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        let motion = true_motion();
        let (source, target) = pairs(&mut rng, 12, &motion, 0.0, &[]);
        let estimate = estimate_rigid_motion(&source, &target, &RansacOptions::default());
        let Some(estimate) = estimate else {
            panic!("no estimate");
        };
        assert_eq!(estimate.inliers, (0..12).collect::<Vec<_>>());
        assert!(estimate.rms < 1e-9, "rms {}", estimate.rms);
        assert!(rotation_error_degrees(&estimate.transform.rotation, &motion.rotation) < 1e-9);
        assert!(distance(estimate.transform.translation, motion.translation) < 1e-12);
    }

    #[test]
    fn too_few_pairs_give_none() {
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        let (source, target) = pairs(&mut rng, 5, &true_motion(), 0.0, &[]);
        assert!(estimate_rigid_motion(&source, &target, &RansacOptions::default()).is_none());
        // Three pairs are the least that determine a motion, whatever `min_inliers` says.
        let lenient = RansacOptions {
            min_inliers: 0,
            ..RansacOptions::default()
        };
        assert!(estimate_rigid_motion(&source[..2], &target[..2], &lenient).is_none());
        assert!(estimate_rigid_motion(&source[..3], &target[..3], &lenient).is_some());
    }

    #[test]
    fn mismatched_lengths_and_bad_thresholds_give_none() {
        let mut rng = ChaCha8Rng::seed_from_u64(14);
        let (source, target) = pairs(&mut rng, 20, &true_motion(), 0.0, &[]);
        let options = RansacOptions::default();
        assert!(estimate_rigid_motion(&source, &target[..19], &options).is_none());
        for inlier_threshold in [0.0, -0.004, f64::NAN, f64::INFINITY] {
            let bad = RansacOptions {
                inlier_threshold,
                ..options
            };
            assert!(estimate_rigid_motion(&source, &target, &bad).is_none());
        }
        assert!(estimate_rigid_motion(&source, &target, &options).is_some());
    }

    #[test]
    fn unrelated_points_give_no_motion() {
        let mut rng = ChaCha8Rng::seed_from_u64(15);
        let source: Vec<[f64; 3]> = (0..200).map(|_| random_point(&mut rng)).collect();
        let target: Vec<[f64; 3]> = (0..200).map(|_| random_point(&mut rng)).collect();
        assert!(estimate_rigid_motion(&source, &target, &RansacOptions::default()).is_none());
        // Accepting any consensus, with a threshold loose enough (1 cm) that many samples are
        // tried, chance alignments gather a handful of pairs at most (~0.2 per hypothesis
        // besides its sample: a 1 cm ball fills 0.1 % of the box).
        let lenient = RansacOptions {
            inlier_threshold: 0.01,
            min_inliers: 3,
            ..RansacOptions::default()
        };
        let inliers = estimate_rigid_motion(&source, &target, &lenient)
            .map_or(0, |estimate| estimate.inliers.len());
        assert!(
            (3..=8).contains(&inliers),
            "{inliers} inliers among unrelated points"
        );
    }

    #[test]
    fn collinear_points_give_none() {
        let mut rng = ChaCha8Rng::seed_from_u64(16);
        let motion = true_motion();
        let source: Vec<[f64; 3]> = (0..50)
            .map(|_| {
                let s = rng.random_range(-HALF_BOX..HALF_BOX);
                [s, 0.5 * s, DEPTH + 0.2 * s]
            })
            .collect();
        let target: Vec<[f64; 3]> = source.iter().map(|&a| motion.apply(a)).collect();
        assert!(estimate_rigid_motion(&source, &target, &RansacOptions::default()).is_none());
    }

    #[test]
    fn deterministic_per_seed_and_skips_non_finite_pairs() {
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let outliers: Vec<usize> = (0..100).step_by(3).collect();
        let (mut source, mut target) = pairs(&mut rng, 100, &true_motion(), 0.001, &outliers);
        source[1] = [f64::NAN, 0.0, DEPTH];
        target[4] = [0.0, f64::INFINITY, DEPTH];
        let options = RansacOptions {
            seed: 99,
            ..RansacOptions::default()
        };
        let first = estimate_rigid_motion(&source, &target, &options);
        let second = estimate_rigid_motion(&source, &target, &options);
        assert_eq!(first, second);
        let Some(estimate) = first else {
            panic!("no estimate");
        };
        assert!(!estimate.inliers.contains(&1) && !estimate.inliers.contains(&4));
        assert!(estimate.transform.is_finite() && estimate.rms.is_finite());
        assert!(estimate.inliers.len() >= 60);
    }

    #[test]
    fn iteration_count_follows_the_inlier_fraction() {
        // log(0.001) / log(1 − 0.6³) = 28.5.
        assert_eq!(required_iterations(0.6, 0.999, 500), 29);
        assert_eq!(required_iterations(1.0, 0.999, 500), 0);
        assert_eq!(required_iterations(0.0, 0.999, 500), 500);
        assert_eq!(required_iterations(0.05, 0.999, 500), 500);
        assert_eq!(required_iterations(0.6, 1.0, 500), 500);
        assert_eq!(required_iterations(0.6, 0.0, 500), 0);
    }

    #[test]
    fn samples_are_three_distinct_indices() {
        let mut rng = ChaCha8Rng::seed_from_u64(18);
        let mut seen = [0usize; 4];
        for _ in 0..2000 {
            let s = draw_sample(&mut rng, 4);
            assert!(s[0] != s[1] && s[0] != s[2] && s[1] != s[2], "{s:?}");
            for i in s {
                seen[i] += 1;
            }
        }
        // Each index is in 3 of the 4 possible triples: drawn ~1500 times of 2000.
        assert!(seen.iter().all(|&c| (1350..1650).contains(&c)), "{seen:?}");
    }
}
