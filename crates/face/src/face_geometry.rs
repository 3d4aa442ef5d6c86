//! Metric face geometry from 468 landmarks and known intrinsics (paper §3, ERRATA 7–8): the
//! canonical metric face mesh ([`CanonicalMesh`]) is placed in the camera by a rigid pose so that
//! its perspective projection matches the landmarks.
//!
//! Reference: MediaPipe's face-geometry module (`geometry_pipeline.cc`), which solves a weighted
//! orthogonal Procrustes problem between the canonical mesh and the landmarks lifted with their
//! relative depth, on the weighted "Procrustes basis" points. visage does the same for the
//! initial pose (weighted similarity Procrustes, Horn's quaternion method; depth from the
//! recovered scale, `Z = f / σ`), then refines the rigid pose by Gauss–Newton on the
//! perspective reprojection error of all 468 landmarks. The scale stays that of the canonical
//! (average adult) face: with a pinhole camera, face size and distance are otherwise ambiguous.
//!
//! Outputs, in camera coordinates (x right, y down, z forward, metres):
//! - the pose `X_cam = R · X_canonical + t`;
//! - the rigidly fitted canonical vertices `R · X + t`;
//! - the **metric landmarks**: each landmark's pixel back-projected to the z of its fitted
//!   vertex. They reproject exactly onto the detected landmarks (so expressions and non-rigid
//!   motion are kept in the image plane) and carry the fitted metric depth; this is the mesh
//!   ([`face_trimesh`]) that the pipeline rasterises into the face's dense depth.

use visage_camera::{horn_rotation, quaternion_to_matrix, Intrinsics, RigidTransform};
use visage_mesh::TriMesh;

use crate::{CanonicalMesh, FaceError, NUM_LANDMARKS};

/// Gauss–Newton iterations of the pose refinement (it converges in 3–5).
pub const REFINE_ITERATIONS: usize = 15;
/// Landmarks spread over less than this (RMS distance from their centroid, pixels) are
/// degenerate: no face can be fitted.
pub const MIN_LANDMARK_SPREAD_PX: f64 = 1.0;

/// A rigid head pose `X_cam = R · X_canonical + t`.
pub type FacePose = RigidTransform;

/// The metric fit of one face.
#[derive(Clone, Debug, PartialEq)]
pub struct FaceGeometry {
    pub pose: FacePose,
    /// Canonical vertices placed by the pose (468, metres, camera coordinates).
    pub fitted_vertices: Vec<[f64; 3]>,
    /// Landmarks back-projected to their fitted vertex's z (468, metres, camera coordinates).
    pub metric_landmarks: Vec<[f64; 3]>,
    /// Root-mean-square reprojection error of the fitted vertices against the landmarks, pixels.
    pub rms_px: f64,
}

/// Fits the canonical mesh to landmarks `points` (468 × `(x, y, z)`, frame pixels in the visage
/// convention, z relative with the scale of x) seen with intrinsics `k`.
pub fn fit_face_geometry(
    canonical: &CanonicalMesh,
    points: &[[f32; 3]],
    k: &Intrinsics,
) -> Result<FaceGeometry, FaceError> {
    if points.len() != NUM_LANDMARKS {
        return Err(FaceError::InputSize {
            what: "landmarks",
            expected: NUM_LANDMARKS,
            found: points.len(),
        });
    }
    if points.iter().any(|p| p.iter().any(|v| !v.is_finite())) {
        return Err(FaceError::Fit {
            reason: "non-finite landmark".into(),
        });
    }
    let m = &canonical.vertices;
    let q: Vec<[f64; 3]> = points
        .iter()
        .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
        .collect();
    let n = q.len() as f64;
    let mean: [f64; 2] = std::array::from_fn(|a| q.iter().map(|p| p[a]).sum::<f64>() / n);
    let spread = (q
        .iter()
        .map(|p| (p[0] - mean[0]).powi(2) + (p[1] - mean[1]).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    if spread.is_nan() || spread < MIN_LANDMARK_SPREAD_PX {
        return Err(FaceError::Fit {
            reason: format!("degenerate landmarks (spread {spread} px)"),
        });
    }
    // 1. Weighted similarity Procrustes on the basis points: q ≈ σ R m + τ (pixels).
    let (sigma, rotation) = similarity_procrustes(m, &q, &canonical.procrustes_basis);
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(FaceError::Fit {
            reason: format!("degenerate landmarks (Procrustes scale {sigma})"),
        });
    }
    let z = k.focal() / sigma;
    let (mut wsum, mut mc, mut pc) = (0.0, [0.0; 3], [0.0; 2]);
    for &(i, w) in &canonical.procrustes_basis {
        wsum += w;
        for a in 0..3 {
            mc[a] += w * m[i][a];
        }
        for a in 0..2 {
            pc[a] += w * q[i][a];
        }
    }
    let mc = mc.map(|v| v / wsum);
    let pc = pc.map(|v| v / wsum);
    let centre = [(pc[0] - k.cx) / k.fx * z, (pc[1] - k.cy) / k.fy * z, z];
    let rm = mat_vec(&rotation, mc);
    let mut pose = FacePose {
        rotation,
        translation: std::array::from_fn(|a| centre[a] - rm[a]),
    };
    // 2. Gauss–Newton on the perspective reprojection error of all landmarks.
    for _ in 0..REFINE_ITERATIONS {
        let mut h = [[0.0f64; 6]; 6];
        let mut g = [0.0f64; 6];
        for (mi, qi) in m.iter().zip(&q) {
            let rmi = mat_vec(&pose.rotation, *mi);
            let p: [f64; 3] = std::array::from_fn(|a| rmi[a] + pose.translation[a]);
            if p[2] <= 1e-6 {
                continue;
            }
            let (iz, iz2) = (1.0 / p[2], 1.0 / (p[2] * p[2]));
            let r = [
                k.fx * p[0] * iz + k.cx - qi[0],
                k.fy * p[1] * iz + k.cy - qi[1],
            ];
            let dpi = [
                [k.fx * iz, 0.0, -k.fx * p[0] * iz2],
                [0.0, k.fy * iz, -k.fy * p[1] * iz2],
            ];
            // dP/dθ = −[R m]ₓ (left-multiplied rotation update), dP/dt = I.
            let skew = [
                [0.0, rmi[2], -rmi[1]],
                [-rmi[2], 0.0, rmi[0]],
                [rmi[1], -rmi[0], 0.0],
            ];
            for row in 0..2 {
                let mut jrow = [0.0f64; 6];
                for c in 0..3 {
                    jrow[c] = (0..3).map(|a| dpi[row][a] * skew[a][c]).sum();
                    jrow[3 + c] = dpi[row][c];
                }
                for a in 0..6 {
                    g[a] += jrow[a] * r[row];
                    for b in 0..6 {
                        h[a][b] += jrow[a] * jrow[b];
                    }
                }
            }
        }
        for (a, row) in h.iter_mut().enumerate() {
            row[a] *= 1.0 + 1e-6;
        }
        let Some(delta) = solve6(h, g.map(|v| -v)) else {
            break;
        };
        let rot = rotation_from_vector([delta[0], delta[1], delta[2]]);
        pose.rotation = mat_mul(&rot, &pose.rotation);
        for a in 0..3 {
            pose.translation[a] += delta[3 + a];
        }
        if delta.iter().map(|v| v * v).sum::<f64>().sqrt() < 1e-10 {
            break;
        }
    }
    let fitted_vertices: Vec<[f64; 3]> = m.iter().map(|&x| pose.apply(x)).collect();
    if fitted_vertices
        .iter()
        .any(|v| !(v[2] > 0.0 && v.iter().all(|c| c.is_finite())))
    {
        return Err(FaceError::Fit {
            reason: "the metric face fit placed the face behind the camera".into(),
        });
    }
    let mut sq = 0.0;
    let metric_landmarks = fitted_vertices
        .iter()
        .zip(&q)
        .map(|(v, qi)| {
            let p = k.project(*v);
            sq += (p[0] - qi[0]).powi(2) + (p[1] - qi[1]).powi(2);
            [
                (qi[0] - k.cx) / k.fx * v[2],
                (qi[1] - k.cy) / k.fy * v[2],
                v[2],
            ]
        })
        .collect();
    Ok(FaceGeometry {
        pose,
        fitted_vertices,
        metric_landmarks,
        rms_px: (sq / NUM_LANDMARKS as f64).sqrt(),
    })
}

/// Weighted similarity Procrustes `q ≈ σ R p + τ` over `(index, weight)` pairs (Horn 1987, unit
/// quaternion as the top eigenvector of the 4×4 matrix `N`). Returns `(σ, R)`.
fn similarity_procrustes(
    p: &[[f64; 3]],
    q: &[[f64; 3]],
    basis: &[(usize, f64)],
) -> (f64, [[f64; 3]; 3]) {
    let wsum: f64 = basis.iter().map(|b| b.1).sum();
    let mut pc = [0.0; 3];
    let mut qc = [0.0; 3];
    for &(i, w) in basis {
        for a in 0..3 {
            pc[a] += w * p[i][a] / wsum;
            qc[a] += w * q[i][a] / wsum;
        }
    }
    let mut s = [[0.0f64; 3]; 3];
    let mut pp = 0.0;
    for &(i, w) in basis {
        let a: [f64; 3] = std::array::from_fn(|c| p[i][c] - pc[c]);
        let b: [f64; 3] = std::array::from_fn(|c| q[i][c] - qc[c]);
        pp += w * (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        for r in 0..3 {
            for c in 0..3 {
                s[r][c] += w * a[r] * b[c];
            }
        }
    }
    let r = horn_rotation(&s);
    // σ = Σ w bᵀ R a / Σ w |a|².
    let mut num = 0.0;
    for &(i, w) in basis {
        let a: [f64; 3] = std::array::from_fn(|c| p[i][c] - pc[c]);
        let ra = mat_vec(&r, a);
        for c in 0..3 {
            num += w * (q[i][c] - qc[c]) * ra[c];
        }
    }
    (num / pp, r)
}

/// Rodrigues' formula.
fn rotation_from_vector(v: [f64; 3]) -> [[f64; 3]; 3] {
    let th = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if th < 1e-300 {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let h = (0.5 * th).sin() / th;
    quaternion_to_matrix([(0.5 * th).cos(), v[0] * h, v[1] * h, v[2] * h])
}

fn mat_vec(r: &[[f64; 3]; 3], x: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| r[i][0] * x[0] + r[i][1] * x[1] + r[i][2] * x[2])
}

fn mat_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// Solves a 6×6 system by Gaussian elimination with partial pivoting; `None` if singular.
#[allow(clippy::needless_range_loop)]
fn solve6(mut a: [[f64; 6]; 6], mut b: [f64; 6]) -> Option<[f64; 6]> {
    for col in 0..6 {
        let piv = (col..6).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        for row in col + 1..6 {
            let f = a[row][col] / a[col][col];
            for c in col..6 {
                a[row][c] -= f * a[col][c];
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; 6];
    for row in (0..6).rev() {
        let s: f64 = (row + 1..6).map(|c| a[row][c] * x[c]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The fitted face as a triangle mesh in camera coordinates (metres): the metric landmarks as
/// vertices, the canonical triangles and UVs.
pub fn face_trimesh(geometry: &FaceGeometry, canonical: &CanonicalMesh) -> TriMesh {
    let mut mesh = TriMesh::new(
        geometry.metric_landmarks.clone(),
        canonical.triangles.clone(),
    );
    mesh.uvs = canonical.uvs.clone();
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    fn synthetic_mesh() -> CanonicalMesh {
        // A bumpy 468-point "face" (metres), basis = every 7th point.
        let vertices: Vec<[f64; 3]> = (0..NUM_LANDMARKS)
            .map(|i| {
                let (a, b) = ((i % 26) as f64 / 25.0 - 0.5, (i / 26) as f64 / 17.0 - 0.5);
                [
                    0.15 * a,
                    0.2 * b,
                    -0.05 * (1.0 - 4.0 * a * a) + 0.01 * (7.0 * b).sin(),
                ]
            })
            .collect();
        CanonicalMesh {
            vertices,
            uvs: vec![[0.0; 2]; NUM_LANDMARKS],
            triangles: Vec::new(),
            procrustes_basis: (0..NUM_LANDMARKS)
                .step_by(7)
                .map(|i| (i, 1.0 + (i % 3) as f64))
                .collect(),
        }
    }

    #[test]
    fn recovers_a_known_pose_exactly() {
        let mesh = synthetic_mesh();
        let k = Intrinsics::from_fov(640, 480, 60.0).unwrap();
        let truth = FacePose {
            rotation: rotation_from_vector([0.2, -0.35, 0.1]),
            translation: [0.03, -0.02, 0.55],
        };
        // Landmarks: exact projections; relative z in pixels (scale of x) about the centroid.
        let cam: Vec<[f64; 3]> = mesh.vertices.iter().map(|&v| truth.apply(v)).collect();
        let zmean = cam.iter().map(|p| p[2]).sum::<f64>() / cam.len() as f64;
        let pts: Vec<[f32; 3]> = cam
            .iter()
            .map(|p| {
                let uv = k.project(*p);
                [
                    uv[0] as f32,
                    uv[1] as f32,
                    ((p[2] - zmean) * k.fx / zmean) as f32,
                ]
            })
            .collect();
        let fit = fit_face_geometry(&mesh, &pts, &k).unwrap();
        assert!(fit.rms_px < 1e-3, "rms {}", fit.rms_px);
        for a in 0..3 {
            assert!(
                (fit.pose.translation[a] - truth.translation[a]).abs() < 1e-5,
                "t {:?}",
                fit.pose.translation
            );
            for b in 0..3 {
                assert!((fit.pose.rotation[a][b] - truth.rotation[a][b]).abs() < 1e-5);
            }
        }
        for (l, v) in fit.metric_landmarks.iter().zip(&cam) {
            assert!((l[2] - v[2]).abs() < 1e-5);
        }
    }

    #[test]
    fn rejects_wrong_counts_and_nan() {
        let mesh = synthetic_mesh();
        let k = Intrinsics::from_fov(64, 48, 60.0).unwrap();
        assert!(fit_face_geometry(&mesh, &[[0.0; 3]; 10], &k).is_err());
        let mut pts = vec![[1.0f32; 3]; NUM_LANDMARKS];
        pts[3][0] = f32::NAN;
        assert!(fit_face_geometry(&mesh, &pts, &k).is_err());
        // All landmarks at one point: degenerate, an error rather than a panic.
        assert!(fit_face_geometry(&mesh, &vec![[5.0f32, 5.0, 0.0]; NUM_LANDMARKS], &k).is_err());
    }
}
