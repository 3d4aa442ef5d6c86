//! Jitter after removing rigid motion: the root-mean-square distance between two point sets
//! (the same points of a surface in consecutive frames) once the second is rigidly aligned to
//! the first: frame-to-frame motion with the head's rigid motion removed.
//!
//! Alignment is the unweighted least-squares rotation and translation (Kabsch 1976), solved by
//! Horn's closed form in [`visage_camera::RigidTransform::fit`].

use visage_camera::RigidTransform;

/// RMS residual distance (units of the input) between `a` and `b` after the best rigid motion
/// of `b` onto `a`. Pairs where either point is not finite (a point missing in one frame) are
/// left out. `None` for fewer than 3 pairs.
///
/// # Panics
/// If `a` and `b` differ in length.
#[track_caller]
pub fn rigid_residual_rms(a: &[[f64; 3]], b: &[[f64; 3]]) -> Option<f64> {
    assert_eq!(a.len(), b.len(), "point sets of different sizes");
    let finite = |p: &[f64; 3]| p.iter().all(|c| c.is_finite());
    let pairs = || a.iter().zip(b).filter(|(p, q)| finite(p) && finite(q));
    let n = pairs().count();
    if n < 3 {
        return None;
    }
    let fit = RigidTransform::fit(pairs().map(|(p, q)| (*q, *p, 1.0)))?;
    let squares: f64 = pairs()
        .map(|(p, q)| {
            let m = fit.apply(*q);
            (0..3).map(|c| (m[c] - p[c]).powi(2)).sum::<f64>()
        })
        .sum();
    Some((squares / n as f64).sqrt())
}

/// Running mean of the rigid-aligned jitter over consecutive frames of one surface.
#[derive(Clone, Debug, Default)]
pub struct JitterMeter {
    previous: Vec<[f64; 3]>,
    /// Whether `previous` holds the last frame (false after a gap).
    has_previous: bool,
    sum: f64,
    pairs: usize,
}

impl JitterMeter {
    /// Adds a frame; `points` = the surface's points in this frame, in the same order every
    /// frame. The pair with the previous frame counts when there was one (no gap).
    pub fn push(&mut self, points: &[[f64; 3]]) {
        if self.has_previous && self.previous.len() == points.len() {
            if let Some(r) = rigid_residual_rms(&self.previous, points) {
                self.sum += r;
                self.pairs += 1;
            }
        }
        self.previous.clear();
        self.previous.extend_from_slice(points);
        self.has_previous = true;
    }

    /// A frame without a surface: the next frame starts a new pair.
    pub fn gap(&mut self) {
        self.has_previous = false;
    }

    /// Mean over the pairs seen (same unit as the points), `None` without pairs.
    pub fn mean(&self) -> Option<f64> {
        (self.pairs > 0).then(|| self.sum / self.pairs as f64)
    }

    pub fn pairs(&self) -> usize {
        self.pairs
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn cloud(rng: &mut ChaCha8Rng, n: usize) -> Vec<[f64; 3]> {
        (0..n)
            .map(|_| std::array::from_fn(|_| rng.random_range(-0.08..0.08)))
            .collect()
    }

    fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
        let n = axis.iter().map(|v| v * v).sum::<f64>().sqrt();
        let [x, y, z] = axis.map(|v| v / n);
        let (s, c) = angle.sin_cos();
        let t = 1.0 - c;
        [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ]
    }

    fn moved(p: &[[f64; 3]], r: [[f64; 3]; 3], t: [f64; 3]) -> Vec<[f64; 3]> {
        p.iter()
            .map(|x| std::array::from_fn(|i| (0..3).map(|j| r[i][j] * x[j]).sum::<f64>() + t[i]))
            .collect()
    }

    #[test]
    fn a_rigidly_moving_surface_has_no_jitter() {
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        let p = cloud(&mut rng, 500);
        let mut meter = JitterMeter::default();
        for k in 0..10 {
            let r = rotation([0.3, 1.0, 0.1 * k as f64], 0.05 * k as f64);
            meter.push(&moved(&p, r, [0.01 * k as f64, -0.02, 0.5]));
        }
        assert_eq!(meter.pairs(), 9);
        assert!(meter.mean().unwrap() < 1e-9, "{:?}", meter.mean());
    }

    #[test]
    fn independent_noise_of_sigma_gives_sqrt2_sigma() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let p = cloud(&mut rng, 4000);
        let sigma = 1e-3 / 3f64.sqrt(); // per axis, so that the 3-D RMS noise is 1 mm
        let noisy = |rng: &mut ChaCha8Rng, q: &[[f64; 3]]| -> Vec<[f64; 3]> {
            q.iter()
                .map(|x| {
                    std::array::from_fn(|c| {
                        // Box–Muller.
                        let (u, v): (f64, f64) = (rng.random(), rng.random());
                        x[c] + sigma
                            * (-2.0 * (1.0 - u).ln()).sqrt()
                            * (std::f64::consts::TAU * v).cos()
                    })
                })
                .collect()
        };
        let a = noisy(&mut rng, &p);
        let b = noisy(
            &mut rng,
            &moved(&p, rotation([1.0, 0.2, 0.0], 0.3), [0.1, 0.0, 0.2]),
        );
        let r = rigid_residual_rms(&a, &b).unwrap();
        let expected = 2f64.sqrt() * 1e-3;
        assert!((r / expected - 1.0).abs() < 0.03, "{r} vs {expected}");
    }

    #[test]
    fn gaps_break_pairs() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let p = cloud(&mut rng, 10);
        let mut meter = JitterMeter::default();
        meter.push(&p);
        meter.gap();
        meter.push(&p);
        assert_eq!(meter.pairs(), 0);
        assert_eq!(meter.mean(), None);
        assert_eq!(rigid_residual_rms(&p[..2], &p[..2]), None);
        // Missing points are left out of the pair.
        let mut q = p.clone();
        q[3] = [f64::NAN; 3];
        assert!(rigid_residual_rms(&p, &q).unwrap() < 1e-12);
    }
}
