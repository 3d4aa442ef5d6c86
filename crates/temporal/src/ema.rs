//! The exponential moving average: `y_t = α x_t + (1 − α) y_{t−1}`.

use crate::TrackFilter;

/// Exponential moving average with a fixed weight `alpha` ∈ (0, 1] on the new sample (1: no
/// smoothing). Per frame, whatever the frame rate.
#[derive(Clone, Debug)]
pub struct Ema {
    alpha: f64,
    y: Vec<f64>,
}

impl Ema {
    /// # Panics
    /// When `alpha` is not in (0, 1].
    pub fn new(alpha: f64) -> Ema {
        assert!(
            alpha > 0.0 && alpha <= 1.0,
            "EMA weight {alpha} not in (0, 1]"
        );
        Ema {
            alpha,
            y: Vec::new(),
        }
    }
}

impl TrackFilter for Ema {
    fn step(&mut self, x: &[f64], _dt: f64) -> &[f64] {
        if self.y.len() != x.len() {
            self.y = x.to_vec();
        } else {
            for (y, &x) in self.y.iter_mut().zip(x) {
                *y += self.alpha * (x - *y);
            }
        }
        &self.y
    }

    fn reset(&mut self) {
        self.y.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ema_converges_geometrically_to_a_step() {
        let mut f = Ema::new(0.5);
        f.step(&[0.0], 1.0);
        let y: Vec<f64> = (0..3).map(|_| f.step(&[1.0], 1.0)[0]).collect();
        assert_eq!(y, vec![0.5, 0.75, 0.875]);
        f.reset();
        assert_eq!(f.step(&[4.0], 1.0), &[4.0]);
    }
}
