//! The head pose from landmarks with known 3-D positions, under perspective: Gauss–Newton on
//! the weighted reprojection error, with the rotation updated on the left by the exponential
//! map, and a linear estimate of the translation for a given rotation to start from.

use faer::linalg::solvers::Solve;
use faer::Mat;
use visage_camera::{Intrinsics, RigidTransform};

use super::perspective::project_with_jacobian;

/// Levenberg damping added to the Gauss–Newton normal equations, relative to their trace / 6.
pub const POSE_DAMPING: f64 = 1e-6;

/// The translation `t` that best places points `x` (model frame) seen at pixels `pixels`,
/// for the rotation `r`: `(u − c_x)(r₃·x + t_z) = f_x (r₁·x + t_x)` and likewise for v are
/// linear in t; weighted least squares. `None` when the system is singular.
pub fn translation_for_rotation(
    k: &Intrinsics,
    r: &[[f64; 3]; 3],
    x: &[[f64; 3]],
    pixels: &[[f64; 2]],
    weights: &[f64],
) -> Option<[f64; 3]> {
    let mut n = [[0.0; 3]; 3];
    let mut g = [0.0; 3];
    for ((p, l), &w) in x.iter().zip(pixels).zip(weights) {
        if w <= 0.0 {
            continue;
        }
        let rx: [f64; 3] = std::array::from_fn(|i| (0..3).map(|c| r[i][c] * p[c]).sum());
        let (a, b) = ((l[0] - k.cx) / k.fx, (l[1] - k.cy) / k.fy);
        // a (rx_z + t_z) = rx_x + t_x  →  t_x − a t_z = a rx_z − rx_x, likewise for b.
        for (row, rhs) in [
            ([1.0, 0.0, -a], a * rx[2] - rx[0]),
            ([0.0, 1.0, -b], b * rx[2] - rx[1]),
        ] {
            for i in 0..3 {
                g[i] += w * row[i] * rhs;
                for j in 0..3 {
                    n[i][j] += w * row[i] * row[j];
                }
            }
        }
    }
    solve3(n, g)
}

/// Refines `pose` (model frame → camera) by `iterations` Gauss–Newton steps on
/// `Σ w_j ‖π(R x_j + t) − ℓ_j‖²`. Returns the weighted RMS reprojection error (px) after.
pub fn refine_pose(
    k: &Intrinsics,
    pose: &mut RigidTransform,
    x: &[[f64; 3]],
    pixels: &[[f64; 2]],
    weights: &[f64],
    iterations: usize,
) -> f64 {
    for _ in 0..iterations {
        let mut h = Mat::<f64>::zeros(6, 6);
        let mut g = [0.0; 6];
        for ((p, l), &w) in x.iter().zip(pixels).zip(weights) {
            if w <= 0.0 {
                continue;
            }
            let rx = pose.rotate(*p);
            let y: [f64; 3] = std::array::from_fn(|i| rx[i] + pose.translation[i]);
            if y[2] <= 0.0 {
                continue;
            }
            let (u, j) = project_with_jacobian(k, y);
            // ∂Y/∂ω = −[R x]×, ∂Y/∂t = I.
            let skew = [
                [0.0, rx[2], -rx[1]],
                [-rx[2], 0.0, rx[0]],
                [rx[1], -rx[0], 0.0],
            ];
            for r in 0..2 {
                let mut row = [0.0; 6];
                for c in 0..3 {
                    row[c] = (0..3).map(|m| j[r][m] * skew[m][c]).sum();
                    row[3 + c] = j[r][c];
                }
                let res = u[r] - l[r];
                for a in 0..6 {
                    g[a] += w * row[a] * res;
                    for b in 0..6 {
                        h[(a, b)] += w * row[a] * row[b];
                    }
                }
            }
        }
        let damping = POSE_DAMPING * (0..6).map(|i| h[(i, i)]).sum::<f64>() / 6.0;
        for i in 0..6 {
            h[(i, i)] += damping.max(1e-12);
        }
        let Ok(llt) = h.llt(faer::Side::Lower) else {
            break;
        };
        let rhs = Mat::from_fn(6, 1, |i, _| -g[i]);
        let step = llt.solve(&rhs);
        let omega = [step[(0, 0)], step[(1, 0)], step[(2, 0)]];
        let dr = exp_so3(omega);
        pose.rotation = mat3_mul(&dr, &pose.rotation);
        for c in 0..3 {
            pose.translation[c] += step[(3 + c, 0)];
        }
    }
    reprojection_rms(k, pose, x, pixels, weights)
}

/// Weighted RMS reprojection error (px) of `x` placed by `pose`.
pub fn reprojection_rms(
    k: &Intrinsics,
    pose: &RigidTransform,
    x: &[[f64; 3]],
    pixels: &[[f64; 2]],
    weights: &[f64],
) -> f64 {
    let (mut sum, mut total) = (0.0, 0.0);
    for ((p, l), &w) in x.iter().zip(pixels).zip(weights) {
        let u = k.project(pose.apply(*p));
        sum += w * ((u[0] - l[0]).powi(2) + (u[1] - l[1]).powi(2));
        total += w;
    }
    if total > 0.0 {
        (sum / total).sqrt()
    } else {
        0.0
    }
}

/// Rodrigues' formula.
pub fn exp_so3(w: [f64; 3]) -> [[f64; 3]; 3] {
    let theta = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    let k = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]];
    let (a, b) = if theta < 1e-8 {
        (1.0, 0.5)
    } else {
        (theta.sin() / theta, (1.0 - theta.cos()) / (theta * theta))
    };
    let k2 = mat3_mul(&k, &k);
    std::array::from_fn(|i| {
        std::array::from_fn(|j| (i == j) as u8 as f64 + a * k[i][j] + b * k2[i][j])
    })
}

pub fn mat3_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|m| a[i][m] * b[m][j]).sum()))
}

fn solve3(n: [[f64; 3]; 3], g: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&n);
    if d.abs() <= 1e-300 || d.is_nan() {
        return None;
    }
    // Cramer's rule.
    Some(std::array::from_fn(|c| {
        let mut m = n;
        for r in 0..3 {
            m[r][c] = g[r];
        }
        det(&m) / d
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_pose_from_a_rough_start() {
        let k = Intrinsics::from_fov(640, 480, 60.0).unwrap();
        let x: Vec<[f64; 3]> = (0..40)
            .map(|i| {
                let a = i as f64 * 0.7;
                [
                    0.06 * a.sin(),
                    0.08 * (1.3 * a).cos(),
                    0.03 * (2.1 * a).sin(),
                ]
            })
            .collect();
        let truth = RigidTransform {
            rotation: mat3_mul(
                &exp_so3([0.2, -0.4, 0.1]),
                &exp_so3([std::f64::consts::PI, 0.0, 0.0]),
            ),
            translation: [0.02, -0.01, 0.6],
        };
        let pixels: Vec<[f64; 2]> = x.iter().map(|&p| k.project(truth.apply(p))).collect();
        let w = vec![1.0; x.len()];
        let r0 = mat3_mul(
            &exp_so3([0.05, -0.2, 0.0]),
            &exp_so3([std::f64::consts::PI, 0.0, 0.0]),
        );
        let t0 = translation_for_rotation(&k, &r0, &x, &pixels, &w).unwrap();
        let mut pose = RigidTransform {
            rotation: r0,
            translation: t0,
        };
        let rms = refine_pose(&k, &mut pose, &x, &pixels, &w, 10);
        assert!(rms < 1e-6, "{rms}");
        for i in 0..3 {
            assert!((pose.translation[i] - truth.translation[i]).abs() < 1e-8);
        }
    }
}
