//! The landmark network's bias that follows the view, and its correction before the fit.
//!
//! MediaPipe's landmarks are not fixed points of the face: as the head turns they slide
//! against the skin, and most of all under pitch — on renders of ICT-FaceKit heads whose pose
//! is known, a head pitched by ±30° is read about a quarter short, and the residue lands on the
//! expression shapes. The correction is a table, per landmark, of the offset between where the
//! network puts it and where the face's surface point projects, along the head's own x and y
//! axes at that point (metres), as a polynomial of degree 5 in the view — the yaw and pitch of the
//! camera seen from the head.
//!
//! The view the table is read at is the one the *uncorrected* landmarks give (a rigid fit on
//! them, the fit's first step), and the table is learned against that same estimate. The
//! correction therefore never feeds back into the view it is read at: an earlier table read at
//! the corrected pose pulled the pose further with each frame. The table is learned from
//! renders (`visage-eval`'s `landmark_view_correction` example, which regenerates the file);
//! [`ViewCorrection::embedded`] is the one shipped.

use visage_camera::{Intrinsics, RigidTransform};

use crate::binary_reader::Reader;

const EMBEDDED: &[u8] = include_bytes!("../../data/landmark_view_correction.bin");
const MAGIC: &[u8; 8] = b"VSGVIEW\0";
const VERSION: u32 = 1;

/// Terms of the polynomial in the view (yaw y, pitch p, radians): every `yᵃ pᵇ` with
/// `a + b ≤ 5`, by degree (1, y, p, y², y·p, p², …). Degree 5 leaves 2.57 px of the held-out
/// renders' landmark offsets where degree 3 left 2.88 px.
pub const VIEW_TERMS: usize = 21;

/// The polynomial's terms at `view`.
pub fn view_terms(view: [f64; 2]) -> [f64; VIEW_TERMS] {
    let [y, p] = view;
    let mut t = [0.0; VIEW_TERMS];
    let mut i = 0;
    for d in 0..=5 {
        for a in 0..=d {
            t[i] = y.powi(d - a) * p.powi(a);
            i += 1;
        }
    }
    t
}

/// The yaw and pitch (radians) of the camera seen from the head at `pose` (model frame: x to
/// the face's left-to-right, y up, z out of the face), from the point `center` of the model: 0
/// when the face looks straight at the camera, the yaw positive when the camera is on the
/// model's +x side, the pitch positive when it is above. Perspective is included: a head off
/// the optical axis is seen obliquely.
pub fn view_of(pose: &RigidTransform, center: [f64; 3]) -> [f64; 2] {
    let c = pose.apply(center);
    let r = &pose.rotation;
    // The direction to the camera, −c, in the model frame: Rᵀ(−c).
    let v: [f64; 3] = std::array::from_fn(|i| -(0..3).map(|k| r[k][i] * c[k]).sum::<f64>());
    [v[0].atan2(v[2]), v[1].atan2(v[0].hypot(v[2]))]
}

/// The image motion (pixels) of the point `x` (model frame) placed by `pose`, per metre along
/// the model's x and y axes: two columns of the projection's Jacobian, `[[∂u/∂x, ∂u/∂y],
/// [∂v/∂x, ∂v/∂y]]`.
fn head_plane_jacobian(k: &Intrinsics, pose: &RigidTransform, x: [f64; 3]) -> [[f64; 2]; 2] {
    let c = pose.apply(x);
    let iz = 1.0 / c[2];
    let r = &pose.rotation;
    let column = |a: usize| {
        let d = [r[0][a], r[1][a], r[2][a]];
        [
            k.fx * (d[0] - c[0] * d[2] * iz) * iz,
            k.fy * (d[1] - c[1] * d[2] * iz) * iz,
        ]
    };
    let (ax, ay) = (column(0), column(1));
    [[ax[0], ay[0]], [ax[1], ay[1]]]
}

/// The offset of the pixel `seen` from the projection of `x` (model frame) placed by `pose`,
/// along the model's x and y axes at `x` (metres); `None` when the head plane is seen edge-on.
pub fn head_plane_offset(
    k: &Intrinsics,
    pose: &RigidTransform,
    x: [f64; 3],
    seen: [f64; 2],
) -> Option<[f64; 2]> {
    let u = k.project(pose.apply(x));
    let d = [seen[0] - u[0], seen[1] - u[1]];
    let j = head_plane_jacobian(k, pose, x);
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    (det.abs() > 1e-9).then(|| {
        [
            (d[0] * j[1][1] - j[0][1] * d[1]) / det,
            (j[0][0] * d[1] - j[1][0] * d[0]) / det,
        ]
    })
}

/// One tracked view of a known head, to learn the table from: the landmarks the network found
/// (frame pixels), the face's own landmark points (model frame, metres), the true pose and the
/// pose a rigid fit of the uncorrected landmarks gives.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewSample {
    pub landmarks_px: Vec<[f64; 2]>,
    pub points: Vec<[f64; 3]>,
    pub pose: RigidTransform,
    pub estimated_pose: RigidTransform,
}

/// The table: per landmark, the coefficients of its offset along the head's x and y on
/// [`view_terms`], and the range of views it was learned over (it is read at the nearest view
/// inside it).
#[derive(Clone, Debug, PartialEq)]
pub struct ViewCorrection {
    coefficients: Vec<[[f32; VIEW_TERMS]; 2]>,
    max_view: [f64; 2],
}

impl ViewCorrection {
    /// The table shipped with the crate.
    pub fn embedded() -> ViewCorrection {
        match ViewCorrection::parse(EMBEDDED) {
            Ok(t) => t,
            Err(e) => unreachable!("the embedded view correction is checked by a test: {e}"),
        }
    }

    /// Landmarks in the table.
    pub fn landmark_count(&self) -> usize {
        self.coefficients.len()
    }

    /// The largest yaw and pitch (radians) the table was learned over.
    pub fn max_view(&self) -> [f64; 2] {
        self.max_view
    }

    /// Learns the table from `samples` (each view's offsets against the true pose, regressed
    /// on the terms of the view the uncorrected landmarks gave), by least squares per landmark
    /// and axis; `max_view` is the range of the views rendered. `None` when the samples do not
    /// span the polynomial's terms.
    pub fn learn(samples: &[ViewSample], k: &Intrinsics, max_view: [f64; 2]) -> Option<Self> {
        let landmarks = samples.first()?.landmarks_px.len();
        let mut normal = faer::Mat::<f64>::zeros(VIEW_TERMS, VIEW_TERMS);
        let mut rhs = faer::Mat::<f64>::zeros(VIEW_TERMS, 2 * landmarks);
        for s in samples {
            let center = centroid(&s.points);
            let t = view_terms(clamp_view(view_of(&s.estimated_pose, center), max_view));
            for i in 0..VIEW_TERMS {
                for j in 0..VIEW_TERMS {
                    normal[(i, j)] += t[i] * t[j];
                }
            }
            for (l, (&x, &seen)) in s.points.iter().zip(&s.landmarks_px).enumerate() {
                let o = head_plane_offset(k, &s.pose, x, seen)?;
                for i in 0..VIEW_TERMS {
                    rhs[(i, 2 * l)] += t[i] * o[0];
                    rhs[(i, 2 * l + 1)] += t[i] * o[1];
                }
            }
        }
        let llt = normal.llt(faer::Side::Lower).ok()?;
        let x = faer::linalg::solvers::Solve::solve(&llt, &rhs);
        let coefficients = (0..landmarks)
            .map(|l| std::array::from_fn(|a| std::array::from_fn(|t| x[(t, 2 * l + a)] as f32)))
            .collect();
        Some(ViewCorrection {
            coefficients,
            max_view,
        })
    }

    /// Landmark `l`'s offset along the head's x and y (metres) at `view`.
    pub fn offset(&self, l: usize, view: [f64; 2]) -> [f64; 2] {
        let t = view_terms(clamp_view(view, self.max_view));
        self.coefficients[l].map(|c| c.iter().zip(&t).map(|(&c, t)| c as f64 * t).sum())
    }

    /// The landmarks `landmarks_px` with the bias at `view` taken off: each moved by minus its
    /// offset, mapped to pixels at its point `points[l]` placed by `pose`. `pose` is the rigid
    /// fit of the uncorrected landmarks and `view` its [`view_of`] the points' centroid.
    pub fn correct(
        &self,
        k: &Intrinsics,
        pose: &RigidTransform,
        view: [f64; 2],
        points: &[[f64; 3]],
        landmarks_px: &[[f64; 2]],
        out: &mut Vec<[f64; 2]>,
    ) {
        let t = view_terms(clamp_view(view, self.max_view));
        out.clear();
        out.extend(landmarks_px.iter().enumerate().map(|(l, &seen)| {
            let (Some(c), Some(&x)) = (self.coefficients.get(l), points.get(l)) else {
                return seen;
            };
            let o: [f64; 2] = c.map(|c| c.iter().zip(&t).map(|(&c, t)| c as f64 * t).sum());
            let j = head_plane_jacobian(k, pose, x);
            [
                seen[0] - (j[0][0] * o[0] + j[0][1] * o[1]),
                seen[1] - (j[1][0] * o[0] + j[1][1] * o[1]),
            ]
        }));
    }

    /// The file format: magic, version, landmark count, term count, the two view limits and
    /// the coefficients (little-endian f32, landmark by landmark, x then y).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(32 + self.coefficients.len() * 8 * VIEW_TERMS);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&(self.coefficients.len() as u32).to_le_bytes());
        out.extend_from_slice(&(VIEW_TERMS as u32).to_le_bytes());
        for v in self.max_view {
            out.extend_from_slice(&(v as f32).to_le_bytes());
        }
        for c in self.coefficients.iter().flatten().flatten() {
            out.extend_from_slice(&c.to_le_bytes());
        }
        out
    }

    /// Parses [`ViewCorrection::to_bytes`]' format; the error says what is wrong.
    pub fn parse(bytes: &[u8]) -> Result<ViewCorrection, String> {
        let mut r = Reader::new(bytes);
        r.header(MAGIC, VERSION)?;
        let landmarks = r.u32()? as usize;
        let terms = r.u32()? as usize;
        if terms != VIEW_TERMS {
            return Err(format!("{terms} terms, expected {VIEW_TERMS}"));
        }
        let max_view = [r.f32()? as f64, r.f32()? as f64];
        if max_view.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(format!("view limits {max_view:?} are not positive"));
        }
        let mut coefficient = || -> Result<[f32; VIEW_TERMS], String> {
            let mut c = [0.0; VIEW_TERMS];
            for v in &mut c {
                *v = r.f32()?;
                if !v.is_finite() {
                    return Err("a coefficient is not finite".into());
                }
            }
            Ok(c)
        };
        let coefficients = (0..landmarks)
            .map(|_| Ok([coefficient()?, coefficient()?]))
            .collect::<Result<_, String>>()?;
        r.finish()?;
        Ok(ViewCorrection {
            coefficients,
            max_view,
        })
    }
}

fn clamp_view(view: [f64; 2], max_view: [f64; 2]) -> [f64; 2] {
    [
        view[0].clamp(-max_view[0], max_view[0]),
        view[1].clamp(-max_view[1], max_view[1]),
    ]
}

/// The mean of `points`.
pub fn centroid(points: &[[f64; 3]]) -> [f64; 3] {
    let n = points.len().max(1) as f64;
    points
        .iter()
        .fold([0.0; 3], |s, p| [s[0] + p[0], s[1] + p[1], s[2] + p[2]])
        .map(|v| v / n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::rigid_pose::{exp_so3, mat3_mul};
    use crate::fit::FRONTAL;

    fn pose(yaw: f64, pitch: f64) -> RigidTransform {
        RigidTransform {
            rotation: mat3_mul(
                &FRONTAL,
                &mat3_mul(&exp_so3([0.0, yaw, 0.0]), &exp_so3([-pitch, 0.0, 0.0])),
            ),
            translation: [0.0, 0.0, 0.5],
        }
    }

    #[test]
    fn the_view_is_zero_head_on_and_signed_by_the_turn() {
        let v = view_of(&pose(0.0, 0.0), [0.0; 3]);
        assert!(v[0].abs() < 1e-12 && v[1].abs() < 1e-12, "{v:?}");
        let v = view_of(&pose(0.3, 0.0), [0.0; 3]);
        assert!(
            (v[0].abs() - 0.3).abs() < 1e-9 && v[1].abs() < 1e-9,
            "{v:?}"
        );
        let v = view_of(&pose(0.0, 0.2), [0.0; 3]);
        assert!(
            v[0].abs() < 1e-9 && (v[1].abs() - 0.2).abs() < 1e-9,
            "{v:?}"
        );
    }

    /// A bias that is a cubic in the estimated view is learned exactly, taken off exactly, and
    /// the table survives its file format.
    #[test]
    fn a_cubic_bias_is_learned_and_taken_off() {
        let k = Intrinsics::from_fov(640, 480, 55.0).unwrap();
        let points: Vec<[f64; 3]> = (0..6)
            .map(|i| {
                let a = i as f64;
                [
                    0.03 * a.sin(),
                    0.04 * (1.7 * a).cos(),
                    0.02 * (0.9 * a).sin(),
                ]
            })
            .collect();
        let truth = |l: usize, v: [f64; 2]| {
            let s = l as f64 * 1e-3;
            [
                s + 0.01 * v[1] * v[1] - 0.004 * v[0],
                0.002 * v[0] * v[1] + 0.006 * v[1].powi(3),
            ]
        };
        let mut samples = Vec::new();
        for yi in -4..=4 {
            for pi in -3..=3 {
                let p = pose(yi as f64 * 0.1, pi as f64 * 0.1);
                // The estimate is off from the truth; the table is read at the estimate.
                let e = pose(yi as f64 * 0.09, pi as f64 * 0.08);
                let view = view_of(&e, centroid(&points));
                let landmarks_px = points
                    .iter()
                    .enumerate()
                    .map(|(l, &x)| {
                        let o = truth(l, view);
                        let j = head_plane_jacobian(&k, &p, x);
                        let u = k.project(p.apply(x));
                        [
                            u[0] + j[0][0] * o[0] + j[0][1] * o[1],
                            u[1] + j[1][0] * o[0] + j[1][1] * o[1],
                        ]
                    })
                    .collect();
                samples.push(ViewSample {
                    landmarks_px,
                    points: points.clone(),
                    pose: p,
                    estimated_pose: e,
                });
            }
        }
        let table = ViewCorrection::learn(&samples, &k, [0.5, 0.4]).unwrap();
        let table = ViewCorrection::parse(&table.to_bytes()).unwrap();
        let view = |s: &ViewSample| view_of(&s.estimated_pose, centroid(&points));
        for s in &samples {
            for l in 0..points.len() {
                let (o, t) = (table.offset(l, view(s)), truth(l, view(s)));
                assert!(
                    (o[0] - t[0]).abs() < 1e-7 && (o[1] - t[1]).abs() < 1e-7,
                    "{o:?} {t:?}"
                );
            }
        }
        // Taken off at the estimated pose, the landmarks come back near the true projections.
        let s = &samples[40];
        let mut corrected = Vec::new();
        table.correct(
            &k,
            &s.estimated_pose,
            view(s),
            &s.points,
            &s.landmarks_px,
            &mut corrected,
        );
        let error = |seen: &[[f64; 2]]| -> f64 {
            seen.iter()
                .zip(&s.points)
                .map(|(u, &x)| {
                    let v = k.project(s.pose.apply(x));
                    (u[0] - v[0]).hypot(u[1] - v[1])
                })
                .sum()
        };
        let (before, after) = (error(&s.landmarks_px), error(&corrected));
        assert!(after < 0.1 * before, "{before} → {after}");
        assert!(ViewCorrection::parse(&table.to_bytes()[..20]).is_err());
    }

    #[test]
    fn the_embedded_table_parses_and_covers_the_landmarks() {
        let t = ViewCorrection::embedded();
        assert_eq!(
            t.landmark_count(),
            crate::FaceModel::embedded().landmarks.len()
        );
    }
}
