//! How a filtered track is judged against the one it was made from: jitter, deviation, lag.

use serde::Serialize;

/// Largest lag searched, frames (either sign).
pub const MAX_LAG_FRAMES: f64 = 3.0;

/// Jitter, deviation and lag of a track of points (`dim` scalars each) against a reference
/// track, accumulated over one or more segments (frames that follow each other; nothing is
/// measured across a segment's ends).
#[derive(Clone, Debug, Default, Serialize)]
pub struct TrackFigures {
    /// RMS over frames and points of the second difference ‖p(t+1) − 2p(t) + p(t−1)‖.
    pub jitter: f64,
    /// The reference's own jitter, on the same points and frames.
    pub reference_jitter: f64,
    /// Mean distance from the reference.
    pub deviation: f64,
    /// The time shift (frames; positive: behind) that best aligns the track with the
    /// reference, to 0.05 frames: the least-squares distance between `track(t)` and
    /// `reference(t − lag)` (linearly interpolated).
    pub lag_frames: f64,
    #[serde(skip)]
    sums: Sums,
}

#[derive(Clone, Debug, Default)]
struct Sums {
    jitter: f64,
    reference_jitter: f64,
    jitter_count: usize,
    deviation: f64,
    deviation_count: usize,
    /// Per candidate lag: squared distance and count.
    lag: Vec<(f64, usize)>,
}

const LAG_STEP: f64 = 0.05;

fn lag_candidates() -> impl Iterator<Item = f64> {
    let n = (MAX_LAG_FRAMES / LAG_STEP).round() as i64;
    (-n..=n).map(|i| i as f64 * LAG_STEP)
}

impl TrackFigures {
    /// Adds a segment: `track[t]` and `reference[t]` are frame t's points (`dim` scalars each);
    /// `points` selects which points count (`None`: all).
    ///
    /// # Panics
    /// When the two segments differ in length or a frame's length is not a multiple of `dim`.
    pub fn add_segment(
        &mut self,
        track: &[Vec<f64>],
        reference: &[Vec<f64>],
        dim: usize,
        points: Option<&[usize]>,
    ) {
        assert_eq!(track.len(), reference.len(), "segments differ in length");
        let all: Vec<usize>;
        let points = match points {
            Some(p) => p,
            None => {
                all = (0..track.first().map_or(0, |f| f.len() / dim)).collect();
                &all
            }
        };
        let s = &mut self.sums;
        if s.lag.is_empty() {
            s.lag = lag_candidates().map(|_| (0.0, 0)).collect();
        }
        let n = track.len();
        for t in 0..n {
            assert_eq!(track[t].len() % dim, 0, "frame {t} is not whole points");
            for &i in points {
                let r = &reference[t][i * dim..(i + 1) * dim];
                let y = &track[t][i * dim..(i + 1) * dim];
                s.deviation += y
                    .iter()
                    .zip(r)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt();
                s.deviation_count += 1;
                if t >= 1 && t + 1 < n {
                    let second = |x: &[Vec<f64>]| -> f64 {
                        (0..dim)
                            .map(|c| {
                                let at = |u: usize| x[u][i * dim + c];
                                (at(t + 1) - 2.0 * at(t) + at(t - 1)).powi(2)
                            })
                            .sum()
                    };
                    s.jitter += second(track);
                    s.reference_jitter += second(reference);
                    s.jitter_count += 1;
                }
            }
        }
        // Lag: every candidate on the frames where the shifted reference exists.
        for (slot, lag) in s.lag.iter_mut().zip(lag_candidates()) {
            for (t, frame) in track.iter().enumerate() {
                let u = t as f64 - lag;
                let (lo, frac) = (u.floor(), u - u.floor());
                if lo < 0.0 || lo as usize + 1 >= n {
                    continue;
                }
                let lo = lo as usize;
                for &i in points {
                    for c in 0..dim {
                        let k = i * dim + c;
                        let r = reference[lo][k] * (1.0 - frac) + reference[lo + 1][k] * frac;
                        slot.0 += (frame[k] - r).powi(2);
                    }
                    slot.1 += 1;
                }
            }
        }
        self.finish();
    }

    fn finish(&mut self) {
        let s = &self.sums;
        let rms = |sum: f64, count: usize| {
            if count == 0 {
                0.0
            } else {
                (sum / count as f64).sqrt()
            }
        };
        self.jitter = rms(s.jitter, s.jitter_count);
        self.reference_jitter = rms(s.reference_jitter, s.jitter_count);
        self.deviation = if s.deviation_count == 0 {
            0.0
        } else {
            s.deviation / s.deviation_count as f64
        };
        self.lag_frames = s
            .lag
            .iter()
            .zip(lag_candidates())
            .filter(|((_, count), _)| *count > 0)
            .min_by(|((a, na), _), ((b, nb), _)| (a / *na as f64).total_cmp(&(b / *nb as f64)))
            .map_or(0.0, |(_, lag)| lag);
    }

    /// How many times less jitter than the reference (∞ for a still track on a moving one).
    pub fn reduction(&self) -> f64 {
        self.reference_jitter / self.jitter
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wave(t: f64) -> Vec<f64> {
        vec![(0.2 * t).sin() * 10.0, (0.13 * t).cos() * 5.0]
    }

    #[test]
    fn a_delayed_copy_has_its_delay_as_lag() {
        let reference: Vec<Vec<f64>> = (0..100).map(|t| wave(t as f64)).collect();
        let late: Vec<Vec<f64>> = (0..100).map(|t| wave(t as f64 - 1.5)).collect();
        let mut f = TrackFigures::default();
        f.add_segment(&late, &reference, 2, None);
        assert!((f.lag_frames - 1.5).abs() < 0.051, "lag {}", f.lag_frames);
        assert!(f.deviation > 0.5);
        let mut same = TrackFigures::default();
        same.add_segment(&reference, &reference, 2, None);
        assert_eq!((same.lag_frames, same.deviation), (0.0, 0.0));
        assert!((same.reduction() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn jitter_is_the_rms_second_difference_of_the_selected_points() {
        // Point 0 alternates ±1 in x (second difference ±4), point 1 is still.
        let track: Vec<Vec<f64>> = (0..10)
            .map(|t| vec![if t % 2 == 0 { 1.0 } else { -1.0 }, 0.0, 0.0, 0.0])
            .collect();
        let still = vec![vec![0.0; 4]; 10];
        let mut f = TrackFigures::default();
        f.add_segment(&track, &still, 2, Some(&[0]));
        assert!((f.jitter - 4.0).abs() < 1e-12 && f.reference_jitter == 0.0);
        let mut both = TrackFigures::default();
        both.add_segment(&track, &still, 2, None);
        assert!((both.jitter - 8f64.sqrt()).abs() < 1e-12);
        assert!((both.deviation - 0.5).abs() < 1e-12);
    }
}
