//! Where MediaPipe's canonical FaceMesh lies on the ICT-FaceKit face: the correspondence that
//! gives the true 3-D position of every FaceMesh landmark — and so of every face-anchored
//! vertex — in any frame of a synthetic sequence.
//!
//! 1. **Alignment.** The canonical mesh (visage axes: x right, y down, z forward, metres) is
//!    mapped into the ICT model frame (x to the image right, y up, face along +z) by the
//!    similarity `x ↦ s R x + t` that best fits [`LANDMARK_PAIRS`] — eye corners, nose tip,
//!    mouth corners and chin, which both models mark (FaceMesh by landmark index, ICT by its
//!    iBUG-68 landmark vertices) — in the least-squares sense (Umeyama 1991, "Least-squares
//!    estimation of transformation parameters between two point patterns", Eqs. 40–42).
//! 2. **Projection.** Each aligned canonical vertex is moved to the closest point of the ICT
//!    face-region surface ([`Region::Face`] triangles, exact point–triangle distance), which
//!    gives an ICT triangle and barycentric coordinates: a *material* point of the ICT face.
//!
//! The ICT meshes of every identity and expression share one topology, so the anchors, found
//! once on the neutral face, follow the skin through identity, expression and head pose.

use faer::Mat;
use visage_face::CanonicalMesh;
use visage_morphable::{IctModel, Region};

use crate::point_to_mesh::closest_point_barycentric;
use crate::EvalError;

/// `(FaceMesh landmark, iBUG-68 landmark)` pairs of the alignment (0-based indices; "right"
/// is the subject's right, on the image's left): right eye outer and inner corner, left eye
/// inner and outer corner, nose tip, right and left mouth corner, chin.
pub const LANDMARK_PAIRS: [(usize, usize); 8] = [
    (33, 36),
    (133, 39),
    (362, 42),
    (263, 45),
    (1, 30),
    (61, 48),
    (291, 54),
    (152, 8),
];

/// A point of the ICT surface: `Σ_j bary[j] · vertices[triangle[j]]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// ICT vertex indices of the triangle.
    pub triangle: [u32; 3],
    /// Barycentric coordinates (non-negative, summing to 1).
    pub bary: [f64; 3],
}

impl SurfacePoint {
    /// The point on a mesh with the ICT topology (`vertices` indexed as the model's).
    pub fn on(&self, vertices: &[[f64; 3]]) -> [f64; 3] {
        std::array::from_fn(|c| {
            (0..3)
                .map(|j| self.bary[j] * vertices[self.triangle[j] as usize][c])
                .sum()
        })
    }
}

/// The canonical FaceMesh anchored on the ICT face.
#[derive(Clone, Debug, PartialEq)]
pub struct CanonicalCorrespondence {
    /// One per canonical vertex (468, landmark order).
    pub points: Vec<SurfacePoint>,
    /// Scale `s` of the alignment (ICT metres per canonical metre).
    pub scale: f64,
    /// Rotation `R` of the alignment, row-major.
    pub rotation: [[f64; 3]; 3],
    /// Translation `t` of the alignment, metres.
    pub translation: [f64; 3],
    /// RMS distance of the aligned [`LANDMARK_PAIRS`] from their ICT landmarks, metres.
    pub landmark_rms_m: f64,
    /// Per canonical vertex: distance from the aligned vertex to its surface point, metres.
    pub projection_m: Vec<f64>,
}

impl CanonicalCorrespondence {
    /// Aligns `canonical` to the neutral face of `model` and projects its vertices onto the
    /// face region.
    pub fn new(
        model: &IctModel,
        canonical: &CanonicalMesh,
    ) -> Result<CanonicalCorrespondence, EvalError> {
        let src: Vec<[f64; 3]> = LANDMARK_PAIRS
            .iter()
            .map(|&(m, _)| canonical.vertices[m])
            .collect();
        let dst: Vec<[f64; 3]> = LANDMARK_PAIRS
            .iter()
            .map(|&(_, i)| model.neutral[model.landmarks[i] as usize])
            .collect();
        let (scale, rotation, translation) = similarity(&src, &dst)?;
        let align = |x: [f64; 3]| -> [f64; 3] {
            std::array::from_fn(|r| {
                scale * (0..3).map(|c| rotation[r][c] * x[c]).sum::<f64>() + translation[r]
            })
        };
        let landmark_rms_m = (src
            .iter()
            .zip(&dst)
            .map(|(&s, d)| dist2(align(s), *d))
            .sum::<f64>()
            / src.len() as f64)
            .sqrt();
        let face = Region::Face.range();
        let triangles: Vec<[u32; 3]> = model
            .triangles
            .iter()
            .filter(|t| t.iter().all(|&i| face.contains(&(i as usize))))
            .copied()
            .collect();
        let boxes: Vec<([f64; 3], [f64; 3])> = triangles
            .iter()
            .map(|t| {
                let p = t.map(|i| model.neutral[i as usize]);
                (
                    std::array::from_fn(|c| p[0][c].min(p[1][c]).min(p[2][c])),
                    std::array::from_fn(|c| p[0][c].max(p[1][c]).max(p[2][c])),
                )
            })
            .collect();
        let mut points = Vec::with_capacity(canonical.vertices.len());
        let mut projection_m = Vec::with_capacity(canonical.vertices.len());
        for &v in &canonical.vertices {
            let q = align(v);
            let mut best = (
                f64::MAX,
                SurfacePoint {
                    triangle: [0; 3],
                    bary: [1.0, 0.0, 0.0],
                },
            );
            for (t, (lo, hi)) in triangles.iter().zip(&boxes) {
                // The box's distance bounds the triangle's from below.
                let gap: f64 = (0..3)
                    .map(|c| (lo[c] - q[c]).max(q[c] - hi[c]).max(0.0).powi(2))
                    .sum();
                if gap >= best.0 {
                    continue;
                }
                let [a, b, c] = t.map(|i| model.neutral[i as usize]);
                let bary = closest_point_barycentric(q, a, b, c);
                let p = SurfacePoint { triangle: *t, bary };
                let d = dist2(q, p.on(&model.neutral));
                if d < best.0 {
                    best = (d, p);
                }
            }
            points.push(best.1);
            projection_m.push(best.0.sqrt());
        }
        Ok(CanonicalCorrespondence {
            points,
            scale,
            rotation,
            translation,
            landmark_rms_m,
            projection_m,
        })
    }

    /// The canonical vertices on a mesh with the ICT topology (e.g. a synthetic frame's posed
    /// vertices), into `out` (468 entries).
    ///
    /// # Panics
    /// If `out` does not have one entry per canonical vertex or `vertices` lacks a vertex.
    #[track_caller]
    pub fn place(&self, vertices: &[[f64; 3]], out: &mut [[f64; 3]]) {
        assert_eq!(out.len(), self.points.len());
        for (o, p) in out.iter_mut().zip(&self.points) {
            *o = p.on(vertices);
        }
    }
}

/// `(s, R, t)` of `x ↦ s R x + t`.
type Similarity = (f64, [[f64; 3]; 3], [f64; 3]);

fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|c| (a[c] - b[c]).powi(2)).sum()
}

/// Least-squares similarity `dst ≈ s R src + t` (Umeyama 1991, Eqs. 40–42): R from the SVD of
/// the cross-covariance with the reflection guard, `s = tr(D S) / σ²_src`.
fn similarity(src: &[[f64; 3]], dst: &[[f64; 3]]) -> Result<Similarity, EvalError> {
    let n = src.len() as f64;
    let mean = |p: &[[f64; 3]]| -> [f64; 3] {
        std::array::from_fn(|c| p.iter().map(|x| x[c]).sum::<f64>() / n)
    };
    let (ms, md) = (mean(src), mean(dst));
    let mut cov = Mat::<f64>::zeros(3, 3);
    let mut var = 0.0;
    for (s, d) in src.iter().zip(dst) {
        for r in 0..3 {
            for c in 0..3 {
                cov[(r, c)] += (d[r] - md[r]) * (s[c] - ms[c]) / n;
            }
            var += (s[r] - ms[r]).powi(2) / n;
        }
    }
    let degenerate = || EvalError::Degenerate {
        seed: 0,
        reason: "canonical ↔ ICT alignment: degenerate landmark configuration".into(),
    };
    let svd = cov.svd().map_err(|_| degenerate())?;
    let (u, v, sv) = (svd.U(), svd.V(), svd.S().column_vector());
    let det = |m: faer::MatRef<'_, f64>| {
        m[(0, 0)] * (m[(1, 1)] * m[(2, 2)] - m[(1, 2)] * m[(2, 1)])
            - m[(0, 1)] * (m[(1, 0)] * m[(2, 2)] - m[(1, 2)] * m[(2, 0)])
            + m[(0, 2)] * (m[(1, 0)] * m[(2, 1)] - m[(1, 1)] * m[(2, 0)])
    };
    let sign = if det(u) * det(v) < 0.0 { -1.0 } else { 1.0 };
    let d = [1.0, 1.0, sign];
    let rotation: [[f64; 3]; 3] = std::array::from_fn(|r| {
        std::array::from_fn(|c| (0..3).map(|k| u[(r, k)] * d[k] * v[(c, k)]).sum())
    });
    let scale = (0..3).map(|k| sv[k] * d[k]).sum::<f64>() / var;
    if !(scale.is_finite() && scale > 0.0) {
        return Err(degenerate());
    }
    let translation = std::array::from_fn(|r| {
        md[r] - scale * (0..3).map(|c| rotation[r][c] * ms[c]).sum::<f64>()
    });
    Ok((scale, rotation, translation))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn similarity_recovers_a_known_transform() {
        let src = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.0, 0.0, 3.0],
            [1.0, 1.0, 1.0],
        ];
        // 90° about z, then (x, −y, −z): a proper rotation.
        let r = [[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]];
        let (s, t) = (0.37, [0.1, -0.2, 0.3]);
        let dst: Vec<[f64; 3]> = src
            .iter()
            .map(|x| {
                std::array::from_fn(|i| s * (0..3).map(|c| r[i][c] * x[c]).sum::<f64>() + t[i])
            })
            .collect();
        let (s2, r2, t2) = similarity(&src, &dst).unwrap();
        assert!((s2 - s).abs() < 1e-12);
        for i in 0..3 {
            assert!((t2[i] - t[i]).abs() < 1e-12);
            for c in 0..3 {
                assert!((r2[i][c] - r[i][c]).abs() < 1e-12);
            }
        }
    }
}
