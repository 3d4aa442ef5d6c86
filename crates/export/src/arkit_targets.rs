//! The 52 ARKit shapes as morph targets of the run's own mesh, transferred from the fitted face
//! model: each vertex of the mesh (its mean head-coordinate surface) is attached to the
//! closest point of the person's fitted neutral face (the model aligned to the mesh by the
//! 468 landmarks both carry), and a shape's target is the model's expression displacement
//! there, turned into the mesh's frame. So the glb's ARKit targets are the model's real
//! shapes — every one of them meaningful for retargeting, whether this clip used it or not —
//! driven by the run's weight curves; the residual targets carry what they do not explain.

use rayon::prelude::*;
use visage_camera::vec3::distance2;
use visage_camera::RigidTransform;
use visage_mesh::point_to_mesh::closest_point_barycentric;
use visage_morphable::FaceModel;
use visage_rig::{IctSource, ARKIT_BLENDSHAPES, ICT_TO_ARKIT};

use crate::capture::Capture;
use visage_run_folder::file_names;

/// ARKit targets on `base` (the mesh's mean surface, head coordinates, y up, metres), or
/// `None` when the run has no blendshape curves, no fitted identity of the built-in model, or
/// a mesh whose landmarks are unknown.
pub fn arkit_targets(capture: &Capture, base: &[[f64; 3]]) -> Option<Vec<Vec<[f64; 3]>>> {
    capture.blendshapes.as_ref()?;
    let parameters = &capture.metrics["parameters"];
    if parameters["model"].as_str() != Some("embedded") {
        return None;
    }
    let identity: Vec<f64> = read_identity(capture)?;
    let model = FaceModel::embedded();
    let mut neutral = Vec::new();
    model.shape(&identity, &[], &mut neutral);
    // The 468 landmarks on the model and on the mesh.
    let model_landmarks = model.landmark_points(&neutral);
    let mesh_landmarks: Vec<[f64; 3]> = match parameters["mesh"].as_str()? {
        "face" if base.len() >= model_landmarks.len() => base[..model_landmarks.len()].to_vec(),
        "model" if base.len() == neutral.len() => {
            model.landmarks.iter().map(|p| p.on(base)).collect()
        }
        _ => return None,
    };
    // Model frame → mesh frame, a similarity on the landmarks: the scale from their spreads,
    // the rotation from a rigid fit of the centred, scaled points.
    let (c_model, c_mesh) = (centroid(&model_landmarks), centroid(&mesh_landmarks));
    let scale = spread(&mesh_landmarks) / spread(&model_landmarks).max(f64::MIN_POSITIVE);
    let fit = RigidTransform::fit(model_landmarks.iter().zip(&mesh_landmarks).map(|(a, b)| {
        (
            std::array::from_fn(|k| scale * (a[k] - c_model[k])),
            std::array::from_fn(|k| b[k] - c_mesh[k]),
            1.0,
        )
    }))?;
    let around = triangles_around(neutral.len(), &model.triangles);
    let attach: Vec<(usize, [f64; 3])> = base
        .par_iter()
        .map(|&p| {
            let q = fit.apply_inverse(std::array::from_fn(|k| p[k] - c_mesh[k]));
            let local = std::array::from_fn(|k| q[k] / scale + c_model[k]);
            closest_point(&neutral, &model.triangles, &around, local)
        })
        .collect();
    let delta_of = |name: &str| -> Option<Vec<[f64; 3]>> {
        let j = model.expression_index(name)?;
        let mode = &model.expressions[j];
        Some(
            attach
                .iter()
                .map(|(t, b)| {
                    let tri = model.triangles[*t];
                    let d: [f64; 3] = std::array::from_fn(|c| {
                        (0..3)
                            .map(|k| b[k] * mode[tri[k] as usize][c] as f64)
                            .sum::<f64>()
                            * scale
                    });
                    fit.rotate(d)
                })
                .collect(),
        )
    };
    let zero = vec![[0.0; 3]; base.len()];
    let targets = ICT_TO_ARKIT
        .iter()
        .map(|source| match source {
            IctSource::Shape(a) => delta_of(a).unwrap_or_else(|| zero.clone()),
            // The weight is the mean of the halves: the target is both halves together.
            IctSource::MeanOf(a, b) => match (delta_of(a), delta_of(b)) {
                (Some(x), Some(y)) => x
                    .iter()
                    .zip(&y)
                    .map(|(p, q)| std::array::from_fn(|c| p[c] + q[c]))
                    .collect(),
                _ => zero.clone(),
            },
            IctSource::Zero => zero.clone(),
        })
        .collect();
    debug_assert_eq!(ICT_TO_ARKIT.len(), ARKIT_BLENDSHAPES.len());
    Some(targets)
}

fn read_identity(capture: &Capture) -> Option<Vec<f64>> {
    let text = std::fs::read_to_string(capture.dir.join(file_names::IDENTITY)).ok()?;
    let json: serde_json::Value = serde_json::from_str(&text).ok()?;
    json["coefficients"]
        .as_array()?
        .iter()
        .map(|v| v.as_f64())
        .collect()
}

fn centroid(points: &[[f64; 3]]) -> [f64; 3] {
    let n = points.len().max(1) as f64;
    std::array::from_fn(|k| points.iter().map(|p| p[k]).sum::<f64>() / n)
}

/// RMS distance of points from their centroid.
fn spread(points: &[[f64; 3]]) -> f64 {
    let n = points.len().max(1) as f64;
    let c = centroid(points);
    (points
        .iter()
        .map(|p| (0..3).map(|k| (p[k] - c[k]).powi(2)).sum::<f64>())
        .sum::<f64>()
        / n)
        .sqrt()
}

/// Corners whose incident triangles are searched for a point's closest point.
const NEAREST_CORNERS: usize = 4;

/// The triangle of `vertices` closest to `p` and the barycentric coordinates of the closest
/// point on it, searched among the triangles around the [`NEAREST_CORNERS`] nearest vertices
/// (`around[v]`: the triangles at vertex v) — where it lies on a mesh of well-shaped triangles.
fn closest_point(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    around: &[Vec<usize>],
    p: [f64; 3],
) -> (usize, [f64; 3]) {
    let mut nearest = [(f64::INFINITY, 0usize); NEAREST_CORNERS];
    for (v, &q) in vertices.iter().enumerate() {
        let d = distance2(q, p);
        if d < nearest[NEAREST_CORNERS - 1].0 {
            nearest[NEAREST_CORNERS - 1] = (d, v);
            nearest.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
    }
    let mut best = (f64::INFINITY, 0, [1.0, 0.0, 0.0]);
    for &(_, v) in nearest.iter().filter(|(d, _)| d.is_finite()) {
        for &t in &around[v] {
            let [a, b, c] = triangles[t].map(|i| vertices[i as usize]);
            let bary = closest_point_barycentric(p, a, b, c);
            let q: [f64; 3] =
                std::array::from_fn(|k| bary[0] * a[k] + bary[1] * b[k] + bary[2] * c[k]);
            let d = distance2(q, p);
            if d < best.0 {
                best = (d, t, bary);
            }
        }
    }
    (best.1, best.2)
}

/// The triangles at each vertex.
fn triangles_around(vertex_count: usize, triangles: &[[u32; 3]]) -> Vec<Vec<usize>> {
    let mut around = vec![Vec::new(); vertex_count];
    for (t, tri) in triangles.iter().enumerate() {
        for &v in tri {
            around[v as usize].push(t);
        }
    }
    around
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_closest_triangle_is_found_among_the_nearest_corners() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let vertices = [a, b, c, [1.0, 1.0, 0.0]];
        let triangles = [[0, 1, 2], [1, 3, 2]];
        let around = triangles_around(4, &triangles);
        let (t, bary) = closest_point(&vertices, &triangles, &around, [0.9, 0.9, 0.1]);
        assert_eq!(t, 1);
        assert!((bary.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }
}
