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
//!    Where two parts of the face touch in the neutral pose, the nearest surface can be the
//!    wrong one — the closed mouth's inner-lip landmarks can land on the other lip, and then
//!    follow the wrong lip when the mouth opens (20 px off on a real clip) — so FaceMesh's
//!    lip and eyelid landmarks ([`LOWER_LIP`], [`UPPER_LIP`], the `*_LID` lists, MediaPipe's
//!    `FACEMESH_LIPS` and eye contours) only look at triangles that move with the matching
//!    blendshape (`jawOpen`, `eyeBlink_L/R`) — or that do not.
//!
//! 3. **Calibration.** The ICT identity and expression that best match the canonical face are
//!    fitted (ridge solves in 3-D, the expression bounded to [0, 1]: the canonical face has its
//!    lips a little apart), the canonical face re-aligned to that surface and projected again
//!    ([`CALIBRATION_ROUNDS`]); what remains between each landmark and its surface point is
//!    kept as that landmark's offset. The canonical face is then exactly an ICT face with
//!    that identity and expression, and a face fits with expression weights that measure the
//!    face, instead of spending them on the two models' different notions of a landmark.
//!
//! The ICT meshes of every identity and expression share one topology, so the anchors, found
//! once on the neutral face, follow the skin through identity, expression and head pose.

use faer::linalg::solvers::Solve;
use faer::Mat;
use visage_camera::vec3::{distance2, norm};
use visage_mesh::point_to_mesh::closest_point_barycentric;

use crate::fit::bounded_least_squares::BoxQp;

use crate::{IctModel, MorphableError, Region};

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

/// FaceMesh's lower-lip landmarks, the middle of the outer and inner contours (the points
/// next to the corners sit where both lips meet and are left free).
pub const LOWER_LIP: [usize; 10] = [181, 84, 17, 314, 405, 178, 87, 14, 317, 402];
/// FaceMesh's upper-lip landmarks, the middle of the outer and inner contours.
pub const UPPER_LIP: [usize; 10] = [39, 37, 0, 267, 269, 81, 82, 13, 312, 311];
/// The subject's right eye's upper and lower lid contour (FaceMesh, corners excluded).
pub const RIGHT_UPPER_LID: [usize; 7] = [246, 161, 160, 159, 158, 157, 173];
pub const RIGHT_LOWER_LID: [usize; 7] = [7, 163, 144, 145, 153, 154, 155];
/// The subject's left eye's upper and lower lid contour.
pub const LEFT_UPPER_LID: [usize; 7] = [466, 388, 387, 386, 385, 384, 398];
pub const LEFT_LOWER_LID: [usize; 7] = [249, 390, 373, 374, 380, 381, 382];

/// A triangle "moves with" a blendshape when its vertices move this far on average at weight
/// 1 (metres); lip landmarks need [`LIP_MOTION_M`] under `jawOpen`.
const MOVES_M: f64 = 0.002;
/// The lower lip moves at least this far with `jawOpen`, the upper lip less.
const LIP_MOTION_M: f64 = 0.005;

/// Which triangles a landmark may lie on.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Part {
    Any,
    /// Mean motion under the expression at least (true) or below (false) the threshold.
    Moving {
        expression: &'static str,
        threshold: f64,
        moves: bool,
    },
}

fn part_of(landmark: usize) -> Part {
    let moving = |expression, threshold, moves| Part::Moving {
        expression,
        threshold,
        moves,
    };
    if LOWER_LIP.contains(&landmark) {
        moving("jawOpen", LIP_MOTION_M, true)
    } else if UPPER_LIP.contains(&landmark) {
        moving("jawOpen", LIP_MOTION_M, false)
    } else if RIGHT_UPPER_LID.contains(&landmark) {
        moving("eyeBlink_R", MOVES_M, true)
    } else if RIGHT_LOWER_LID.contains(&landmark) {
        moving("eyeBlink_R", MOVES_M, false)
    } else if LEFT_UPPER_LID.contains(&landmark) {
        moving("eyeBlink_L", MOVES_M, true)
    } else if LEFT_LOWER_LID.contains(&landmark) {
        moving("eyeBlink_L", MOVES_M, false)
    } else {
        Part::Any
    }
}

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
    /// Per canonical vertex: the aligned vertex minus its surface point on the calibrated face
    /// (ICT model frame, metres) — where FaceMesh puts the landmark off the ICT surface.
    pub offsets_m: Vec<[f64; 3]>,
    /// The calibrated identity: the ICT face closest to the canonical face (weights of the
    /// model's identity modes).
    pub identity: Vec<f64>,
    /// The canonical face's own expression in the calibration (weights of the model's
    /// expression modes).
    pub expression: Vec<f64>,
}

impl CanonicalCorrespondence {
    /// Aligns the canonical FaceMesh `canonical` (its 468 vertices, visage axes, metres) to the
    /// neutral face of `model` and projects its vertices onto the face region.
    ///
    /// # Errors
    /// A degenerate landmark configuration (the alignment has no unique solution).
    pub fn new(
        model: &IctModel,
        canonical: &[[f64; 3]],
    ) -> Result<CanonicalCorrespondence, MorphableError> {
        let src: Vec<[f64; 3]> = LANDMARK_PAIRS.iter().map(|&(m, _)| canonical[m]).collect();
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
            .map(|(&s, d)| distance2(align(s), *d))
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
        // Mean vertex motion of each triangle under an expression at weight 1.
        let motion = |name: &str| -> Option<Vec<f64>> {
            let mode = &model.expression_modes[model.expression_index(name)?];
            Some(
                triangles
                    .iter()
                    .map(|t| t.iter().map(|&i| norm(mode[i as usize])).sum::<f64>() / 3.0)
                    .collect(),
            )
        };
        let motions: Vec<(&str, Option<Vec<f64>>)> = ["jawOpen", "eyeBlink_L", "eyeBlink_R"]
            .into_iter()
            .map(|name| (name, motion(name)))
            .collect();
        let allowed = |landmark: usize, t: usize| match part_of(landmark) {
            Part::Any => true,
            Part::Moving {
                expression,
                threshold,
                moves,
            } => match motions.iter().find(|(n, _)| *n == expression) {
                Some((_, Some(m))) => (m[t] >= threshold) == moves,
                _ => true,
            },
        };
        let mut similarity_fit = (scale, rotation, translation);
        let mut surface = model.neutral.clone();
        let mut aligned: Vec<[f64; 3]> = canonical.iter().map(|&v| align(v)).collect();
        let (mut points, mut projection_m) = project(&aligned, &surface, &triangles, &allowed);
        let mut identity = vec![0.0; model.identity_modes.len()];
        let mut expression = vec![0.0; model.expression_modes.len()];
        // Calibration: this average face's own identity on the ICT model, then project again.
        for _ in 0..CALIBRATION_ROUNDS {
            (identity, expression) = fit_shape(model, &points, &aligned);
            model_surface(model, &identity, &expression, &mut surface);
            let targets: Vec<[f64; 3]> = points.iter().map(|p| p.on(&surface)).collect();
            similarity_fit = similarity(canonical, &targets)?;
            let (s, r, t) = similarity_fit;
            aligned = canonical
                .iter()
                .map(|x| {
                    std::array::from_fn(|i| s * (0..3).map(|c| r[i][c] * x[c]).sum::<f64>() + t[i])
                })
                .collect();
            (points, projection_m) = project(&aligned, &surface, &triangles, &allowed);
        }
        let (scale, rotation, translation) = similarity_fit;
        let offsets_m = points
            .iter()
            .zip(&aligned)
            .map(|(p, a)| {
                let q = p.on(&surface);
                std::array::from_fn(|c| a[c] - q[c])
            })
            .collect();
        Ok(CanonicalCorrespondence {
            points,
            scale,
            rotation,
            translation,
            landmark_rms_m,
            projection_m,
            offsets_m,
            identity,
            expression,
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

/// Rounds of the calibration that fits the ICT identity to the canonical face and projects
/// again: the canonical face is an average face, the ICT neutral another one; matched in shape,
/// the nearest surface point is the same part of the face more often.
pub const CALIBRATION_ROUNDS: usize = 3;

/// The priors' scale in the calibration: identity modes are N(0, 1), the canonical vertices'
/// distance to the model surface counts in units of this (metres).
const CALIBRATION_SIGMA_M: f64 = 0.002;

/// Prior standard deviation of an expression weight in the calibration.
const CALIBRATION_EXPRESSION_PRIOR: f64 = 0.5;

/// Alternations of the identity and the expression solve in the calibration.
const CALIBRATION_ALTERNATIONS: usize = 10;

/// Each aligned point's closest point on the triangles (of `surface`) it may lie on, and the
/// distance.
fn project(
    aligned: &[[f64; 3]],
    surface: &[[f64; 3]],
    triangles: &[[u32; 3]],
    allowed: &dyn Fn(usize, usize) -> bool,
) -> (Vec<SurfacePoint>, Vec<f64>) {
    let boxes: Vec<([f64; 3], [f64; 3])> = triangles
        .iter()
        .map(|t| {
            let p = t.map(|i| surface[i as usize]);
            (
                std::array::from_fn(|c| p[0][c].min(p[1][c]).min(p[2][c])),
                std::array::from_fn(|c| p[0][c].max(p[1][c]).max(p[2][c])),
            )
        })
        .collect();
    let mut points = Vec::with_capacity(aligned.len());
    let mut distances = Vec::with_capacity(aligned.len());
    for (landmark, &q) in aligned.iter().enumerate() {
        let mut best = (
            f64::MAX,
            SurfacePoint {
                triangle: [0; 3],
                bary: [1.0, 0.0, 0.0],
            },
        );
        for (index, (t, (lo, hi))) in triangles.iter().zip(&boxes).enumerate() {
            if !allowed(landmark, index) {
                continue;
            }
            // The box's distance bounds the triangle's from below.
            let gap: f64 = (0..3)
                .map(|c| (lo[c] - q[c]).max(q[c] - hi[c]).max(0.0).powi(2))
                .sum();
            if gap >= best.0 {
                continue;
            }
            let [a, b, c] = t.map(|i| surface[i as usize]);
            let bary = closest_point_barycentric(q, a, b, c);
            let p = SurfacePoint { triangle: *t, bary };
            let d = distance2(q, p.on(surface));
            if d < best.0 {
                best = (d, p);
            }
        }
        points.push(best.1);
        distances.push(best.0.sqrt());
    }
    (points, distances)
}

/// The identity `p` and expression `e ∈ [0, 1]` whose surface points `points` come closest to
/// `targets` (the canonical face is MediaPipe's neutral, but with its lips a little apart and
/// its own eye opening: those are expressions, not a different notion of the landmarks):
/// alternating `(UᵀU + σ² I) p = Uᵀ(targets − S̄ − B e)` and the box-constrained
/// `(BᵀB + σ²/σ_e² I) e = Bᵀ(targets − S̄ − U p)`, `U`, `B` the modes at the points.
fn fit_shape(
    model: &IctModel,
    points: &[SurfacePoint],
    targets: &[[f64; 3]],
) -> (Vec<f64>, Vec<f64>) {
    let rows = 3 * points.len();
    let basis = |modes: &[Vec<[f64; 3]>]| {
        Mat::<f64>::from_fn(rows, modes.len(), |r, m| {
            let p = points[r / 3];
            (0..3)
                .map(|j| p.bary[j] * modes[m][p.triangle[j] as usize][r % 3])
                .sum::<f64>()
        })
    };
    let (u, b) = (basis(&model.identity_modes), basis(&model.expression_modes));
    let residual = Mat::<f64>::from_fn(rows, 1, |r, _| {
        targets[r / 3][r % 3] - points[r / 3].on(&model.neutral)[r % 3]
    });
    let sigma2 = CALIBRATION_SIGMA_M * CALIBRATION_SIGMA_M;
    let mut uu: Mat<f64> = u.transpose() * &u;
    for i in 0..uu.nrows() {
        uu[(i, i)] += sigma2;
    }
    let mut bb: Mat<f64> = b.transpose() * &b;
    for i in 0..bb.nrows() {
        bb[(i, i)] += sigma2 / (CALIBRATION_EXPRESSION_PRIOR * CALIBRATION_EXPRESSION_PRIOR);
    }
    let (mut p, mut e) = (Mat::<f64>::zeros(u.ncols(), 1), vec![0.0; b.ncols()]);
    let Ok(llt) = uu.llt(faer::Side::Lower) else {
        return (vec![0.0; u.ncols()], e);
    };
    let mut qp = BoxQp::new(e.len());
    for _ in 0..CALIBRATION_ALTERNATIONS {
        let e_mat = Mat::<f64>::from_fn(e.len(), 1, |i, _| e[i]);
        let rhs: Mat<f64> = u.transpose() * (&residual - &b * &e_mat);
        p = llt.solve(&rhs);
        let c: Mat<f64> = b.transpose() * (&residual - &u * &p);
        let c: Vec<f64> = (0..e.len()).map(|i| c[(i, 0)]).collect();
        qp.solve(bb.as_ref(), &c, 0.0, 1.0, &mut e);
    }
    ((0..u.ncols()).map(|i| p[(i, 0)]).collect(), e)
}

/// The model's shape with identity `p` and expression `e`, into `out` (every vertex).
fn model_surface(model: &IctModel, p: &[f64], e: &[f64], out: &mut [[f64; 3]]) {
    out.copy_from_slice(&model.neutral);
    let modes = model.identity_modes.iter().zip(p);
    for (mode, &w) in modes.chain(model.expression_modes.iter().zip(e)) {
        for (o, d) in out.iter_mut().zip(mode) {
            for c in 0..3 {
                o[c] += w * d[c];
            }
        }
    }
}

/// `(s, R, t)` of `x ↦ s R x + t`.
type Similarity = (f64, [[f64; 3]; 3], [f64; 3]);

/// Least-squares similarity `dst ≈ s R src + t` (Umeyama 1991, Eqs. 40–42): R from the SVD of
/// the cross-covariance with the reflection guard, `s = tr(D S) / σ²_src`.
fn similarity(src: &[[f64; 3]], dst: &[[f64; 3]]) -> Result<Similarity, MorphableError> {
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
    let degenerate = || MorphableError::Degenerate {
        what: "canonical FaceMesh ↔ ICT alignment: degenerate landmark configuration",
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
