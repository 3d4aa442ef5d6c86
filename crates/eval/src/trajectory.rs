//! Smooth random trajectories: keyframes joined by smoothstep ease-in/out, with still segments.

use rand::Rng;

/// Frames between keyframes, inclusive range.
pub const SEGMENT_FRAMES: (usize, usize) = (10, 30);

/// `3t² − 2t³`: monotone from 0 to 1 with zero slope at both ends, so a trajectory made of
/// such segments has continuous velocity and stays between its keyframe values.
pub fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A trajectory of `frames` values: keyframes every [`SEGMENT_FRAMES`] frames, each segment
/// either still (probability `still_probability`: the value holds) or a move to a new value
/// drawn by `draw`, eased with [`smoothstep`]. Starts at `draw`'s first value. Every value lies
/// between keyframe values, so bounds on `draw` bound the trajectory.
pub fn keyframe_trajectory<R: Rng + ?Sized>(
    rng: &mut R,
    frames: usize,
    still_probability: f64,
    draw: &mut dyn FnMut(&mut R) -> f64,
) -> Vec<f64> {
    let mut out = Vec::with_capacity(frames);
    let mut current = draw(rng);
    while out.len() < frames {
        let len = rng.random_range(SEGMENT_FRAMES.0..=SEGMENT_FRAMES.1);
        let target = if rng.random::<f64>() < still_probability {
            current
        } else {
            draw(rng)
        };
        for i in 0..len {
            if out.len() == frames {
                break;
            }
            let s = smoothstep(i as f64 / len as f64);
            out.push(current + s * (target - current));
        }
        current = target;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn stays_in_bounds_and_moves_smoothly() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let t = keyframe_trajectory(&mut rng, 500, 0.3, &mut |r| r.random_range(-25.0..25.0));
        assert_eq!(t.len(), 500);
        assert!(t.iter().all(|v| (-25.0..25.0).contains(v)));
        // Largest step: a 50° swing over the shortest segment, eased (peak slope 1.5×).
        let max_step = t
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f64::max);
        assert!(
            max_step <= 1.5 * 50.0 / SEGMENT_FRAMES.0 as f64 + 1e-9,
            "{max_step}"
        );
        // Still segments exist: some consecutive frames are equal.
        assert!(t.windows(2).any(|w| w[0] == w[1]));
    }
}
