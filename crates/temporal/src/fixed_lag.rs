//! The constant-velocity model as a fixed-lag smoother: the estimate of frame `t` is given
//! when frame `t + L` has been seen (Rauch–Tung–Striebel over the last `L` steps). One frame
//! of latency (33 ms at 30 fps) lets a frame's estimate see where the motion went next, which
//! no causal filter can; with `L = 0` it is the filter itself.

use std::collections::VecDeque;

use crate::ConstantVelocity;

/// A frame's filtered state, kept while it may still be smoothed.
struct Entry {
    x: Vec<f64>,
    v: Vec<f64>,
    /// Filtered covariance.
    p: [[f64; 2]; 2],
    /// Interval to the next frame and the next frame's predicted covariance, once it came.
    next: Option<(f64, [[f64; 2]; 2])>,
}

/// Fixed-lag constant-velocity smoother.
pub struct FixedLagSmoother {
    filter: ConstantVelocity,
    lag: usize,
    history: VecDeque<Entry>,
    /// Frames given out since the last reset.
    given: usize,
    seen: usize,
}

impl FixedLagSmoother {
    /// A smoother with the filter's acceleration-to-noise ratio (1/s², see
    /// [`ConstantVelocity`]) and a latency of `lag` frames.
    pub fn new(accel_ratio: f64, lag: usize) -> FixedLagSmoother {
        FixedLagSmoother {
            filter: ConstantVelocity::new(accel_ratio),
            lag,
            history: VecDeque::new(),
            given: 0,
            seen: 0,
        }
    }

    /// The filter's acceleration-to-noise ratio (1/s²).
    pub fn accel_ratio(&self) -> f64 {
        self.filter.accel_ratio
    }

    /// The latency, frames.
    pub fn lag(&self) -> usize {
        self.lag
    }

    /// Takes the next sample (`dt` seconds after the previous); returns the estimate of the
    /// frame `lag` frames back once there is one.
    pub fn push(&mut self, x: &[f64], dt: f64) -> Option<Vec<f64>> {
        let predicted = self.filter.advance(x, dt);
        if predicted.is_none() {
            self.history.clear();
        }
        if let (Some(last), Some(p)) = (self.history.back_mut(), predicted) {
            last.next = Some((dt, p));
        }
        let (x, v, p) = self.filter.state();
        self.history.push_back(Entry {
            x: x.to_vec(),
            v: v.to_vec(),
            p,
            next: None,
        });
        self.seen += 1;
        if self.history.len() > self.lag {
            let out = self.smoothed(0);
            self.history.pop_front();
            self.given += 1;
            Some(out)
        } else {
            None
        }
    }

    /// The estimates of the frames not given out yet, oldest first (smoothed with what came
    /// after them); then forgets everything (a cut, a lost face, the end).
    pub fn finish(&mut self) -> Vec<Vec<f64>> {
        let out = (0..self.history.len()).map(|i| self.smoothed(i)).collect();
        self.reset();
        out
    }

    /// Forgets everything without giving the waiting frames out.
    pub fn reset(&mut self) {
        self.history.clear();
        self.filter = ConstantVelocity::new(self.filter.accel_ratio);
        self.given = 0;
        self.seen = 0;
    }

    /// Frames taken but not given out yet.
    pub fn waiting(&self) -> usize {
        self.seen - self.given
    }

    /// The smoothed position of history entry `i` given every later entry (RTS backwards
    /// from the newest).
    fn smoothed(&self, i: usize) -> Vec<f64> {
        let last = self.history.len() - 1;
        let newest = &self.history[last];
        let (mut sx, mut sv) = (newest.x.clone(), newest.v.clone());
        for k in (i..last).rev() {
            let e = &self.history[k];
            let Some((dt, pp)) = e.next else {
                unreachable!("every entry but the newest has a successor");
            };
            // C = P Fᵀ (P_pred)⁻¹ with F = [[1, dt], [0, 1]].
            let [[a, b], [_, d]] = e.p;
            let pft = [[a + dt * b, b], [b + dt * d, d]];
            let det = pp[0][0] * pp[1][1] - pp[0][1] * pp[1][0];
            let inv = [
                [pp[1][1] / det, -pp[0][1] / det],
                [-pp[1][0] / det, pp[0][0] / det],
            ];
            let c = [
                [
                    pft[0][0] * inv[0][0] + pft[0][1] * inv[1][0],
                    pft[0][0] * inv[0][1] + pft[0][1] * inv[1][1],
                ],
                [
                    pft[1][0] * inv[0][0] + pft[1][1] * inv[1][0],
                    pft[1][0] * inv[0][1] + pft[1][1] * inv[1][1],
                ],
            ];
            for j in 0..sx.len() {
                let dx = sx[j] - (e.x[j] + dt * e.v[j]);
                let dv = sv[j] - e.v[j];
                sx[j] = e.x[j] + c[0][0] * dx + c[0][1] * dv;
                sv[j] = e.v[j] + c[1][0] * dx + c[1][1] * dv;
            }
        }
        sx
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TrackFilter;

    fn noisy(t: usize) -> f64 {
        (0.1 * t as f64).sin() * 5.0 + ((t as f64 * 12.9898).sin() * 43758.5453).fract() - 0.5
    }

    #[test]
    fn lag_zero_is_the_filter() {
        let mut s = FixedLagSmoother::new(200.0, 0);
        let mut f = ConstantVelocity::new(200.0);
        for t in 0..50 {
            let a = s.push(&[noisy(t)], 1.0 / 30.0).unwrap();
            assert_eq!(a, f.step(&[noisy(t)], 1.0 / 30.0));
        }
        assert!(s.finish().is_empty());
    }

    #[test]
    fn every_frame_comes_out_once_in_order_and_closer_to_the_truth() {
        let truth = |t: usize| (0.1 * t as f64).sin() * 5.0;
        let mut out = Vec::new();
        let mut s = FixedLagSmoother::new(200.0, 2);
        let mut f = ConstantVelocity::new(200.0);
        let mut filtered = Vec::new();
        for t in 0..200 {
            out.extend(s.push(&[noisy(t)], 1.0 / 30.0));
            filtered.push(f.step(&[noisy(t)], 1.0 / 30.0)[0]);
        }
        assert_eq!(s.waiting(), 2);
        out.extend(s.finish());
        assert_eq!(out.len(), 200);
        let err =
            |y: &dyn Fn(usize) -> f64| (20..200).map(|t| (y(t) - truth(t)).powi(2)).sum::<f64>();
        let (smooth, causal) = (err(&|t| out[t][0]), err(&|t| filtered[t]));
        assert!(smooth < 0.8 * causal, "{smooth} vs {causal}");
    }
}
