//! Taubin λ|μ smoothing (Taubin, "A signal processing approach to fair surface design",
//! SIGGRAPH 1995): the classic non-shrinking mesh-fairing baseline.

use faer::Mat;
use visage_mesh::OneRing;

/// Taubin's shrink step λ.
pub const TAUBIN_LAMBDA: f64 = 0.5;
/// Taubin's inflate step μ; |μ| > λ > 0 keeps the mesh from shrinking.
pub const TAUBIN_MU: f64 = -0.53;

/// Applies `iterations` Taubin passes to the vertex field `x` (#V × 3, metres) in place: each
/// pass is `x ← x + λ U(x)` then `x ← x + μ U(x)` with the umbrella operator
/// `U(x)_i = mean_{j ∈ N(i)} x_j − x_i` over the one-ring (isolated vertices stay put).
/// `scratch` is resized to #V × 3.
///
/// # Panics
/// If `ring` has another vertex count than `x` has rows.
#[track_caller]
pub fn taubin_smooth(x: &mut Mat<f64>, ring: &OneRing, iterations: usize, scratch: &mut Mat<f64>) {
    let n = x.nrows();
    assert!(ring.len() == n);
    scratch.resize_with(n, 3, |_, _| 0.0);
    for _ in 0..iterations {
        for step in [TAUBIN_LAMBDA, TAUBIN_MU] {
            for i in 0..n {
                let nb = ring.of(i);
                for c in 0..3 {
                    scratch[(i, c)] = if nb.is_empty() {
                        0.0
                    } else {
                        nb.iter().map(|&j| x[(j as usize, c)]).sum::<f64>() / nb.len() as f64
                            - x[(i, c)]
                    };
                }
            }
            for i in 0..n {
                for c in 0..3 {
                    x[(i, c)] += step * scratch[(i, c)];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 9×9 grid of unit spacing.
    fn grid() -> (usize, Vec<[u32; 3]>) {
        let m = 9u32;
        let mut t = Vec::new();
        for j in 0..m - 1 {
            for i in 0..m - 1 {
                let a = j * m + i;
                t.push([a, a + 1, a + m + 1]);
                t.push([a, a + m + 1, a + m]);
            }
        }
        ((m * m) as usize, t)
    }

    #[test]
    fn keeps_planes_and_damps_zigzag() {
        let (n, t) = grid();
        let ring = OneRing::new(n, &t);
        let mut scratch = Mat::zeros(0, 0);
        // An affine field is a fixed point in the interior (the umbrella of a linear function is
        // 0 on this symmetric stencil); the boundary moves, and a pass (two steps) carries that
        // two rings inwards, so vertices two rings in are untouched after one pass.
        let mut x = Mat::from_fn(n, 3, |i, c| {
            [(i % 9) as f64, (i / 9) as f64, 0.1 * (i % 9) as f64 + 0.5][c]
        });
        let before = x.clone();
        taubin_smooth(&mut x, &ring, 1, &mut scratch);
        let interior = |i: usize| (2..7).contains(&(i % 9)) && (2..7).contains(&(i / 9));
        for i in (0..n).filter(|&i| interior(i)) {
            for c in 0..3 {
                assert!((x[(i, c)] - before[(i, c)]).abs() < 1e-9);
            }
        }
        // A checkerboard in z is damped strongly.
        let mut z = Mat::from_fn(n, 3, |i, c| {
            if c == 2 {
                ((i % 9 + i / 9) % 2) as f64
            } else {
                0.0
            }
        });
        let amplitude = |m: &Mat<f64>| (m[(40, 2)] - m[(41, 2)]).abs();
        let a0 = amplitude(&z);
        taubin_smooth(&mut z, &ring, 10, &mut scratch);
        assert!(amplitude(&z) < 0.2 * a0, "{} vs {a0}", amplitude(&z));
    }
}
