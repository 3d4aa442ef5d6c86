//! Least-squares rigid alignment of corresponding point sets (Horn 1987, closed form with unit
//! quaternions): the rotation part is shared by the face fit (a similarity) and the
//! face-anchored fusion's frame-to-frame head motion (a rigid motion).

use crate::RigidTransform;

/// The rotation `R` maximising `Σ w bᵀ R a` for the cross-covariance `s = Σ w a bᵀ` of centred
/// point pairs `a → b` (Horn's method: the top eigenvector of a symmetric 4 × 4 matrix).
pub fn horn_rotation(s: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let n = [
        [
            s[0][0] + s[1][1] + s[2][2],
            s[1][2] - s[2][1],
            s[2][0] - s[0][2],
            s[0][1] - s[1][0],
        ],
        [
            s[1][2] - s[2][1],
            s[0][0] - s[1][1] - s[2][2],
            s[0][1] + s[1][0],
            s[2][0] + s[0][2],
        ],
        [
            s[2][0] - s[0][2],
            s[0][1] + s[1][0],
            -s[0][0] + s[1][1] - s[2][2],
            s[1][2] + s[2][1],
        ],
        [
            s[0][1] - s[1][0],
            s[2][0] + s[0][2],
            s[1][2] + s[2][1],
            -s[0][0] - s[1][1] + s[2][2],
        ],
    ];
    quaternion_to_matrix(top_eigenvector4(n))
}

impl RigidTransform {
    /// The rigid motion `T` minimising `Σ w ‖T a − b‖²` over weighted pairs `(a, b, w)`;
    /// `None` when the weights sum to zero.
    pub fn fit(pairs: impl Iterator<Item = ([f64; 3], [f64; 3], f64)> + Clone) -> Option<Self> {
        let (mut wsum, mut ca, mut cb) = (0.0, [0.0; 3], [0.0; 3]);
        for (a, b, w) in pairs.clone() {
            wsum += w;
            for k in 0..3 {
                ca[k] += w * a[k];
                cb[k] += w * b[k];
            }
        }
        if wsum.is_nan() || wsum <= 0.0 {
            return None;
        }
        let (ca, cb) = (ca.map(|v| v / wsum), cb.map(|v| v / wsum));
        let mut s = [[0.0; 3]; 3];
        for (a, b, w) in pairs {
            for r in 0..3 {
                for c in 0..3 {
                    s[r][c] += w * (a[r] - ca[r]) * (b[c] - cb[c]);
                }
            }
        }
        let rotation = horn_rotation(&s);
        let mut fit = RigidTransform {
            rotation,
            translation: [0.0; 3],
        };
        let rc = fit.rotate(ca);
        fit.translation = std::array::from_fn(|k| cb[k] - rc[k]);
        Some(fit)
    }
}

/// Eigenvector of the largest eigenvalue of a symmetric 4×4 matrix (cyclic Jacobi).
#[allow(clippy::needless_range_loop)]
fn top_eigenvector4(mut a: [[f64; 4]; 4]) -> [f64; 4] {
    let mut v = [[0.0; 4]; 4];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for _ in 0..50 {
        let off: f64 = (0..4)
            .flat_map(|i| (0..4).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i][j] * a[i][j])
            .sum();
        if off < 1e-30 {
            break;
        }
        for p in 0..3 {
            for q in p + 1..4 {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = 0.5 * (a[q][q] - a[p][p]) / a[p][q];
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..4 {
                    let (akp, akq) = (a[k][p], a[k][q]);
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for k in 0..4 {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    let best = (0..4)
        .max_by(|&i, &j| a[i][i].total_cmp(&a[j][j]))
        .unwrap_or(0);
    std::array::from_fn(|k| v[k][best])
}

/// The rotation matrix of a quaternion `(w, x, y, z)` (normalised first).
pub fn quaternion_to_matrix(q: [f64; 4]) -> [[f64; 3]; 3] {
    let n = (q.iter().map(|v| v * v).sum::<f64>()).sqrt().max(1e-300);
    let [w, x, y, z] = q.map(|v| v / n);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_recovers_a_rigid_motion() {
        let (c, s) = (0.4f64.cos(), 0.4f64.sin());
        let truth = RigidTransform {
            rotation: [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
            translation: [0.1, -0.2, 0.6],
        };
        let a: Vec<[f64; 3]> = (0..20)
            .map(|i| {
                let t = i as f64;
                [(t * 0.7).sin(), (t * 1.3).cos(), (t * 0.31).sin() * 0.5]
            })
            .collect();
        let fit = RigidTransform::fit(a.iter().map(|&p| (p, truth.apply(p), 1.0))).unwrap();
        for r in 0..3 {
            for k in 0..3 {
                assert!((fit.rotation[r][k] - truth.rotation[r][k]).abs() < 1e-12);
            }
            assert!((fit.translation[r] - truth.translation[r]).abs() < 1e-12);
        }
        assert!(RigidTransform::fit(a.iter().map(|&p| (p, p, 0.0))).is_none());
    }
}
