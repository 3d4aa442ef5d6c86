//! [`MorphAnimation`]: a captured surface sequence as a rigid head motion plus a few morph
//! targets, the way glTF (and three.js, Blender, Unreal, Unity) animate a mesh.
//!
//! Each meshed frame's surface is taken into head coordinates with its pose (the metric face
//! fit), so what is left is the face's own deformation. Named targets, when given (the ARKit
//! shapes with their weight curves), explain what they can; the rest — the fused surface's
//! per-frame residual — is encoded by its principal components: the fewest that bring the
//! root-mean-square vertex error under [`RESIDUAL_TOLERANCE_M`] (at most
//! [`MAX_RESIDUAL_TARGETS`]), each scaled so that its weights span [0, 1]. Why this encoding: a face's deformations over a clip lie close to a
//! low-dimensional space, so a few dozen dense targets plus one weight per target and frame
//! replace one target per frame (or per key frame) — the file grows with the clip by
//! `4 × targets` bytes a frame instead of `12 × vertices`; sparse accessors do not help,
//! since every vertex of a fused surface moves a little in every frame.

use faer::Mat;
use visage_camera::RigidTransform;

use crate::capture::Capture;
use crate::ExportError;

/// The root-mean-square vertex error (metres) the residual targets must reach.
pub const RESIDUAL_TOLERANCE_M: f64 = 5e-5;
/// The most residual targets.
pub const MAX_RESIDUAL_TARGETS: usize = 64;
/// Frames the residual basis is computed from, at most (evenly spaced; every frame is then
/// projected onto it).
const BASIS_FRAMES: usize = 600;

/// Named targets to use before the residual: a delta per vertex (head coordinates, y up) and a
/// weight per processed frame.
pub struct NamedTargets {
    pub names: Vec<String>,
    pub deltas: Vec<Vec<[f64; 3]>>,
    /// Per processed frame (as [`Capture::frames`]), one weight per target.
    pub weights: Vec<Vec<f32>>,
}

/// A surface sequence as glTF animates it.
pub struct MorphAnimation {
    /// The rest surface: the mean head-coordinate surface, y up (metres).
    pub base: Vec<[f32; 3]>,
    /// Target names: the named targets first, then `residual_NN`.
    pub names: Vec<String>,
    /// Per target, a delta per vertex.
    pub targets: Vec<Vec<[f32; 3]>>,
    /// Key frame times (seconds from the first key frame).
    pub times: Vec<f32>,
    /// Seconds of the first key frame since the input's start.
    pub start_s: f64,
    /// Per key frame, every target's weight.
    pub weights: Vec<Vec<f32>>,
    /// Per key frame, the head's translation and rotation (quaternion x, y, z, w), y up.
    pub translations: Vec<[f32; 3]>,
    pub rotations: Vec<[f32; 4]>,
    /// Named targets among [`MorphAnimation::targets`].
    pub named_targets: usize,
    /// The share of the surfaces' deformation (variance about the mean surface) the named
    /// targets and their weights explain; negative when they add more than they explain.
    pub named_explained: Option<f64>,
    /// Root-mean-square and largest vertex error of the encoding against the captured
    /// surfaces, metres.
    pub rms_error_m: f64,
    pub max_error_m: f64,
}

/// Camera coordinates → y up: a half turn about x.
const FLIP: [f64; 3] = [1.0, -1.0, -1.0];

impl MorphAnimation {
    /// Encodes the meshed frames of `capture`; `named` may give targets for the mean
    /// head-coordinate surface it is called with (y up, metres).
    ///
    /// # Errors
    /// No frame has a mesh.
    pub fn encode(
        capture: &Capture,
        named: impl FnOnce(&[[f64; 3]]) -> Option<NamedTargets>,
    ) -> Result<Self, ExportError> {
        let keys: Vec<usize> = capture.meshed().map(|(k, _)| k).collect();
        if keys.is_empty() {
            return Err(ExportError::Empty {
                path: capture.dir.clone(),
            });
        }
        let n = capture.vertex_count();
        let poses = held_poses(capture);
        // Head-coordinate surfaces, y up: q = C · R⁻¹ (p − t).
        let mut rows = Mat::<f64>::zeros(keys.len(), 3 * n);
        for (r, &k) in keys.iter().enumerate() {
            for (v, p) in capture.surface(k).chunks_exact(3).enumerate() {
                let q = poses[k].apply_inverse([p[0] as f64, p[1] as f64, p[2] as f64]);
                for c in 0..3 {
                    rows[(r, 3 * v + c)] = FLIP[c] * q[c];
                }
            }
        }
        let mut base: Vec<f64> = (0..3 * n)
            .map(|j| (0..keys.len()).map(|r| rows[(r, j)]).sum::<f64>() / keys.len() as f64)
            .collect();
        for r in 0..keys.len() {
            for (j, b) in base.iter().enumerate() {
                rows[(r, j)] -= b;
            }
        }
        let mut names = Vec::new();
        let mut targets: Vec<Vec<[f32; 3]>> = Vec::new();
        let mut weights = vec![Vec::new(); keys.len()];
        let base_points: Vec<[f64; 3]> = base.chunks_exact(3).map(|b| [b[0], b[1], b[2]]).collect();
        let energy = |rows: &Mat<f64>| rows.norm_l2().powi(2);
        let before = energy(&rows);
        let mut named_explained = None;
        if let Some(named) = named(&base_points) {
            // The rest surface is the one at zero weights: the mean surface less the mean
            // weights' shapes, so the rows keep only the weights' variation.
            let mean_w: Vec<f64> = (0..named.deltas.len())
                .map(|j| {
                    keys.iter()
                        .map(|&k| named.weights[k][j] as f64)
                        .sum::<f64>()
                        / keys.len() as f64
                })
                .collect();
            for (delta, &m) in named.deltas.iter().zip(&mean_w) {
                for (v, d) in delta.iter().enumerate() {
                    for c in 0..3 {
                        base[3 * v + c] -= m * d[c];
                    }
                }
            }
            // rows −= (W − w̄) · B, frames × targets times targets × 3n.
            let centred = Mat::<f64>::from_fn(keys.len(), named.deltas.len(), |r, j| {
                named.weights[keys[r]][j] as f64 - mean_w[j]
            });
            let shapes = Mat::<f64>::from_fn(named.deltas.len(), 3 * n, |j, i| {
                named.deltas[j][i / 3][i % 3]
            });
            rows -= &centred * &shapes;
            for (w, &k) in weights.iter_mut().zip(&keys) {
                w.extend_from_slice(&named.weights[k]);
            }
            names.extend(named.names.iter().cloned());
            targets.extend(named.deltas.iter().map(|d| to_f32(d)));
            named_explained = Some(1.0 - energy(&rows) / before.max(f64::MIN_POSITIVE));
        }
        let named_targets = names.len();
        let (components, coefficients) = principal_components(&rows, n);
        for (j, component) in components.iter().enumerate() {
            // Weights in [0, 1] (importers such as Blender's clamp shape keys to that range):
            // the target spans the component's range over the clip, and the rest surface sits
            // at its lowest coefficient.
            let (lo, hi) = coefficients
                .iter()
                .map(|c| c[j])
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
                    (lo.min(c), hi.max(c))
                });
            let range = (hi - lo).max(f64::MIN_POSITIVE);
            for (b, d) in base.iter_mut().zip(component) {
                *b += lo * d;
            }
            names.push(format!("residual_{j:02}"));
            targets.push(
                component
                    .chunks_exact(3)
                    .map(|d| [d[0], d[1], d[2]].map(|x| (x * range) as f32))
                    .collect(),
            );
            for (r, c) in coefficients.iter().enumerate() {
                weights[r].push(((c[j] - lo) / range) as f32);
            }
        }
        let base: Vec<[f32; 3]> = base
            .chunks_exact(3)
            .map(|b| [b[0] as f32, b[1] as f32, b[2] as f32])
            .collect();
        let (rms_error_m, max_error_m) =
            encoding_error(capture, &keys, &poses, &base, &targets, &weights);
        let start_s = capture.frames[keys[0]].time_s;
        let mut times: Vec<f32> = keys
            .iter()
            .map(|&k| (capture.frames[k].time_s - start_s) as f32)
            .collect();
        // Strictly increasing, as glTF requires (timestamps can repeat in broken streams).
        for i in 1..times.len() {
            if times[i] <= times[i - 1] {
                times[i] = f32::from_bits(times[i - 1].to_bits() + 1);
            }
        }
        let mut rotations: Vec<[f32; 4]> = Vec::with_capacity(keys.len());
        let mut translations = Vec::with_capacity(keys.len());
        for &k in &keys {
            let pose = &poses[k];
            let r: [[f64; 3]; 3] = std::array::from_fn(|i| {
                std::array::from_fn(|j| FLIP[i] * pose.rotation[i][j] * FLIP[j])
            });
            let mut q = quaternion(&r);
            // The same rotation, on the side of the previous key's, so interpolation takes the
            // short way.
            if let Some(prev) = rotations.last() {
                if (0..4).map(|i| prev[i] * q[i]).sum::<f32>() < 0.0 {
                    q = q.map(|x| -x);
                }
            }
            rotations.push(q);
            translations.push(std::array::from_fn(|c| {
                (FLIP[c] * pose.translation[c]) as f32
            }));
        }
        Ok(MorphAnimation {
            base,
            names,
            targets,
            times,
            start_s,
            weights,
            translations,
            rotations,
            named_targets,
            named_explained,
            rms_error_m,
            max_error_m,
        })
    }

    /// The surface at key frame `r`, head coordinates, y up.
    pub fn surface_at(&self, r: usize) -> Vec<[f32; 3]> {
        morph(&self.base, &self.targets, &self.weights[r])
    }
}

fn to_f32(d: &[[f64; 3]]) -> Vec<[f32; 3]> {
    d.iter().map(|p| p.map(|x| x as f32)).collect()
}

fn morph(base: &[[f32; 3]], targets: &[Vec<[f32; 3]>], weights: &[f32]) -> Vec<[f32; 3]> {
    let mut out = base.to_vec();
    for (t, &w) in targets.iter().zip(weights) {
        if w == 0.0 {
            continue;
        }
        for (o, d) in out.iter_mut().zip(t) {
            for c in 0..3 {
                o[c] += w * d[c];
            }
        }
    }
    out
}

/// Every frame's pose; a frame without one holds the nearest earlier one (the first one
/// before any), the identity when no frame has one.
fn held_poses(capture: &Capture) -> Vec<RigidTransform> {
    let first = capture
        .frames
        .iter()
        .find_map(|f| f.pose)
        .unwrap_or_default();
    let mut held = first;
    capture
        .frames
        .iter()
        .map(|f| {
            if let Some(p) = f.pose {
                held = p;
            }
            held
        })
        .collect()
}

/// The leading principal components of the rows of `d` (frames × 3n, centred) that bring the
/// RMS vertex error under [`RESIDUAL_TOLERANCE_M`], and each row's coefficients. From the
/// eigenvectors of the frames' Gram matrix `D Dᵀ` (frames × frames: a clip has far fewer
/// frames than coordinates), on at most [`BASIS_FRAMES`] evenly spaced frames; every frame is
/// then projected onto the components.
fn principal_components(d: &Mat<f64>, n: usize) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let frames = d.nrows();
    let pick: Vec<usize> = if frames <= BASIS_FRAMES {
        (0..frames).collect()
    } else {
        (0..BASIS_FRAMES)
            .map(|i| i * frames / BASIS_FRAMES)
            .collect()
    };
    let sample = Mat::<f64>::from_fn(pick.len(), d.ncols(), |i, j| d[(pick[i], j)]);
    let gram = &sample * sample.transpose();
    let Ok(eigen) = gram.self_adjoint_eigen(faer::Side::Lower) else {
        return (Vec::new(), vec![Vec::new(); frames]);
    };
    let (u, s) = (eigen.U(), eigen.S().column_vector());
    // Eigenvalues ascend: the largest last.
    let energy: Vec<f64> = (0..s.nrows()).rev().map(|i| s[i].max(0.0)).collect();
    let denominator = (pick.len() * n).max(1) as f64;
    let mut left: f64 = energy.iter().sum();
    let mut k = 0;
    while k < energy.len().min(MAX_RESIDUAL_TARGETS)
        && (left / denominator).sqrt() > RESIDUAL_TOLERANCE_M
        && energy[k] > 0.0
    {
        left -= energy[k];
        k += 1;
    }
    // Component j = sampleᵀ u_j / σ_j (unit length).
    let last = s.nrows();
    let u_k = Mat::<f64>::from_fn(pick.len(), k, |i, j| {
        u[(i, last - 1 - j)] / energy[j].sqrt()
    });
    let basis = sample.transpose() * &u_k;
    let coefficients = d * &basis;
    (
        (0..k)
            .map(|j| (0..d.ncols()).map(|i| basis[(i, j)]).collect())
            .collect(),
        (0..frames)
            .map(|r| (0..k).map(|j| coefficients[(r, j)]).collect())
            .collect(),
    )
}

/// RMS and largest vertex distance between the encoded and the captured surfaces (camera
/// coordinates, as played back: node transform after the morph).
fn encoding_error(
    capture: &Capture,
    keys: &[usize],
    poses: &[RigidTransform],
    base: &[[f32; 3]],
    targets: &[Vec<[f32; 3]>],
    weights: &[Vec<f32>],
) -> (f64, f64) {
    let (mut sum, mut max, mut count) = (0.0, 0.0f64, 0usize);
    for (r, &k) in keys.iter().enumerate() {
        let surface = morph(base, targets, &weights[r]);
        for (q, p) in surface.iter().zip(capture.surface(k).chunks_exact(3)) {
            let head = [0, 1, 2].map(|c| FLIP[c] * q[c] as f64);
            let back = poses[k].apply(head);
            let e2: f64 = (0..3).map(|c| (back[c] - p[c] as f64).powi(2)).sum();
            sum += e2;
            max = max.max(e2.sqrt());
            count += 1;
        }
    }
    ((sum / count.max(1) as f64).sqrt(), max)
}

/// A rotation matrix's unit quaternion `[x, y, z, w]` (Shepperd's method: the largest of the
/// four squared components first, for accuracy).
fn quaternion(r: &[[f64; 3]; 3]) -> [f32; 4] {
    let trace = r[0][0] + r[1][1] + r[2][2];
    let q = if trace > 0.0 {
        let s = (trace + 1.0).sqrt() * 2.0;
        [
            (r[2][1] - r[1][2]) / s,
            (r[0][2] - r[2][0]) / s,
            (r[1][0] - r[0][1]) / s,
            0.25 * s,
        ]
    } else if r[0][0] > r[1][1] && r[0][0] > r[2][2] {
        let s = (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt() * 2.0;
        [
            0.25 * s,
            (r[0][1] + r[1][0]) / s,
            (r[0][2] + r[2][0]) / s,
            (r[2][1] - r[1][2]) / s,
        ]
    } else if r[1][1] > r[2][2] {
        let s = (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt() * 2.0;
        [
            (r[0][1] + r[1][0]) / s,
            0.25 * s,
            (r[1][2] + r[2][1]) / s,
            (r[0][2] - r[2][0]) / s,
        ]
    } else {
        let s = (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt() * 2.0;
        [
            (r[0][2] + r[2][0]) / s,
            (r[1][2] + r[2][1]) / s,
            0.25 * s,
            (r[1][0] - r[0][1]) / s,
        ]
    };
    let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    q.map(|x| (x / norm) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::capture::CaptureFrame;
    use visage_camera::Intrinsics;
    use visage_mesh::TriMesh;

    /// A moving, turning surface that deforms along two shapes: the encoding needs two
    /// residual targets, plays every frame back exactly, and keeps its weights in [0, 1].
    #[test]
    fn a_two_shape_deformation_under_head_motion_plays_back() {
        let n = 12;
        let rest: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                [
                    0.01 * i as f64,
                    0.02 * (i % 3) as f64,
                    0.005 * (i % 4) as f64,
                ]
            })
            .collect();
        let shape = |j: usize| -> Vec<[f64; 3]> {
            (0..n)
                .map(|i| [0.0, 0.002 * ((i + j) % 5) as f64, 0.001 * (j as f64 + 1.0)])
                .collect()
        };
        let (a, b) = (shape(0), shape(2));
        let mut frames = Vec::new();
        let mut surfaces = Vec::new();
        for k in 0..20 {
            let t = k as f64 / 30.0;
            let angle = 0.3 * (3.0 * t).sin();
            let (c, s) = (angle.cos(), angle.sin());
            let pose = RigidTransform {
                rotation: [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
                translation: [0.01 * k as f64, 0.0, 0.5],
            };
            let (wa, wb) = ((5.0 * t).sin(), (7.0 * t).cos());
            for i in 0..n {
                let head = std::array::from_fn(|m| rest[i][m] + wa * a[i][m] + wb * b[i][m]);
                surfaces.extend(pose.apply(head).map(|x| x as f32));
            }
            frames.push(CaptureFrame {
                index: k,
                time_s: t,
                meshed: true,
                pose: Some(pose),
            });
        }
        let capture = Capture {
            dir: "synthetic".into(),
            intrinsics: Intrinsics {
                width: 64,
                height: 64,
                fx: 50.0,
                fy: 50.0,
                cx: 31.5,
                cy: 31.5,
            },
            input: "synthetic".into(),
            mesh: TriMesh::new(rest.clone(), vec![[0, 1, 2]]),
            frames,
            surfaces,
            blendshapes: None,
            metrics: serde_json::Value::Null,
        };
        let animation = MorphAnimation::encode(&capture, |_| None).unwrap();
        assert_eq!(animation.targets.len(), 2, "{:?}", animation.names);
        assert!(animation.max_error_m < 1e-6, "{}", animation.max_error_m);
        assert!(animation
            .weights
            .iter()
            .flatten()
            .all(|w| (0.0..=1.0).contains(w)));
        assert_eq!(animation.times.len(), 20);
        assert!((animation.times[19] - 19.0 / 30.0).abs() < 1e-6);
    }

    #[test]
    fn quaternions_rotate_like_their_matrices() {
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        for r in [
            [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
            [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
            [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]],
            [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]],
        ] {
            let [x, y, z, w] = quaternion(&r).map(|v| v as f64);
            let m = visage_camera::quaternion_to_matrix([w, x, y, z]);
            for i in 0..3 {
                for j in 0..3 {
                    assert!((m[i][j] - r[i][j]).abs() < 1e-6, "{r:?} → {m:?}");
                }
            }
        }
    }
}
