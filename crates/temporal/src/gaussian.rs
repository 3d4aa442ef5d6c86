//! The centred Gaussian: the offline baseline, which sees the frames on both sides.

/// Smooths every scalar of `track` over time with a Gaussian of `sigma` frames, truncated at
/// 3σ and renormalised where the clip ends. `sigma` ≤ 0 returns the track unchanged.
pub fn gaussian_smooth(track: &[Vec<f64>], sigma: f64) -> Vec<Vec<f64>> {
    if sigma <= 0.0 {
        return track.to_vec();
    }
    let radius = (3.0 * sigma).ceil() as isize;
    let kernel: Vec<f64> = (-radius..=radius)
        .map(|j| (-0.5 * (j as f64 / sigma).powi(2)).exp())
        .collect();
    let n = track.len() as isize;
    (0..n)
        .map(|t| {
            let mut out = vec![0.0; track[t as usize].len()];
            let mut total = 0.0;
            for (j, w) in (-radius..=radius).zip(&kernel) {
                let u = t + j;
                if (0..n).contains(&u) {
                    total += w;
                    for (o, x) in out.iter_mut().zip(&track[u as usize]) {
                        *o += w * x;
                    }
                }
            }
            out.iter_mut().for_each(|o| *o /= total);
            out
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_is_kept_and_an_impulse_spread() {
        let line: Vec<Vec<f64>> = (0..20).map(|t| vec![2.0 * t as f64]).collect();
        let smooth = gaussian_smooth(&line, 1.0);
        for t in 3..17 {
            assert!((smooth[t][0] - line[t][0]).abs() < 1e-12);
        }
        let mut impulse = vec![vec![0.0]; 15];
        impulse[7][0] = 1.0;
        let s = gaussian_smooth(&impulse, 1.0);
        let sum: f64 = s.iter().map(|v| v[0]).sum();
        assert!((sum - 1.0).abs() < 1e-12 && (s[6][0] - s[8][0]).abs() < 1e-15);
        assert!((s[7][0] - 0.399).abs() < 1e-3);
    }
}
