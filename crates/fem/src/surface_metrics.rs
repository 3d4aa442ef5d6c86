//! The paper's surface-quality metrics, defined exactly (ERRATA 13).
//!
//! - **mean |H|**: the mean over interior vertices of `|H_i| = ‖(L x)_i‖ / (2 A_i)`, with `L` the
//!   cotangent Laplacian of the 3-D mesh (`(L x)_i = ½ Σ_j (cot α_ij + cot β_ij)(x_i − x_j)`,
//!   Meyer et al. 2003) and `A_i` the mixed Voronoi area (the paper's `A_i` in (5.2); as
//!   [`crate::surface_geometry`] computes them, equal to libigl's). Units: 1/metre. The
//!   **curvature-improvement factor** is mean |H| of the raw surface divided by mean |H| after
//!   regularisation. It can be below 1: mean |H| counts the real curvature of the face (a nose
//!   tip bends at ~1/(5 mm)) as much as noise, so a surface whose noise is small next to its
//!   shape — the face fit's surface, smooth by construction — has little to remove, and a
//!   regularised surface that follows the features more sharply (or a fusion that adds real
//!   detail the raw surface lacked) shows a factor at or below 1. It is a smoothing figure,
//!   not an accuracy one: compare it with the error against ground truth (`visage eval`).
//! - **roughness**: the mean over interior vertices of the angle (radians) between the vertex
//!   normal and the normalised mean of its one-ring neighbours' normals. Vertex normals are
//!   area-weighted face normals.
//!
//! Boundary vertices are excluded from both means: there the Laplacian measures the boundary's
//! curvature, not the surface's.

use visage_camera::vec3::{cross, dot, norm, sub};
use visage_mesh::OneRing;

/// Per-frame metric evaluation on a mesh of fixed connectivity; buffers are allocated once.
#[derive(Clone, Debug)]
pub struct SurfaceMetrics {
    triangles: Vec<[u32; 3]>,
    ring: OneRing,
    interior: Vec<bool>,
    laplace: Vec<[f64; 3]>,
    area: Vec<f64>,
    normals: Vec<[f64; 3]>,
}

/// Mean |H| and roughness of one surface.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SurfaceQuality {
    /// Mean absolute mean curvature, 1/m.
    pub mean_abs_h: f64,
    /// Mean normal deviation from the one-ring, radians.
    pub roughness: f64,
}

impl SurfaceMetrics {
    /// Prepares the evaluation for `vertex_count` vertices, `triangles` and the boundary flags
    /// (#V; `true` = on the boundary).
    pub fn new(vertex_count: usize, triangles: &[[u32; 3]], boundary: &[bool]) -> Self {
        let ring = OneRing::new(vertex_count, triangles);
        let interior = (0..vertex_count)
            .map(|i| !boundary.get(i).copied().unwrap_or(false) && !ring.of(i).is_empty())
            .collect();
        SurfaceMetrics {
            triangles: triangles.to_vec(),
            ring,
            interior,
            laplace: vec![[0.0; 3]; vertex_count],
            area: vec![0.0; vertex_count],
            normals: vec![[0.0; 3]; vertex_count],
        }
    }

    /// Evaluates mean |H| and roughness of the surface with vertex positions `x` (#V × 3,
    /// metres). Allocates nothing.
    ///
    /// # Panics
    /// If `x` does not have #V entries.
    #[track_caller]
    pub fn evaluate(&mut self, x: &[[f64; 3]]) -> SurfaceQuality {
        assert!(x.len() == self.area.len());
        self.laplace.iter_mut().for_each(|v| *v = [0.0; 3]);
        self.area.iter_mut().for_each(|a| *a = 0.0);
        self.normals.iter_mut().for_each(|n| *n = [0.0; 3]);
        for t in &self.triangles {
            let p = t.map(|i| x[i as usize]);
            let n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
            let double_area = norm(n);
            if double_area <= 0.0 {
                continue;
            }
            // cot of the angle at each corner.
            let cot: [f64; 3] = std::array::from_fn(|k| {
                let (i, j) = ((k + 1) % 3, (k + 2) % 3);
                dot(sub(p[i], p[k]), sub(p[j], p[k])) / double_area
            });
            let obtuse = cot.iter().position(|&c| c < 0.0);
            for k in 0..3 {
                let (i, j) = ((k + 1) % 3, (k + 2) % 3);
                let half_cot = 0.5 * cot[k];
                let d = sub(p[i], p[j]);
                let (vi, vj) = (t[i] as usize, t[j] as usize);
                for (c, dc) in d.iter().enumerate() {
                    self.laplace[vi][c] += half_cot * dc;
                    self.laplace[vj][c] -= half_cot * dc;
                }
                // The mixed Voronoi area (Meyer et al.; `crate::mixed_areas`).
                let (e_ki, e_kj) = (sub(p[i], p[k]), sub(p[j], p[k]));
                self.area[t[k] as usize] += match obtuse {
                    Some(o) if o == k => double_area / 4.0,
                    Some(_) => double_area / 8.0,
                    None => 0.125 * (cot[j] * dot(e_ki, e_ki) + cot[i] * dot(e_kj, e_kj)),
                };
                for (acc, nc) in self.normals[t[k] as usize].iter_mut().zip(n) {
                    *acc += nc;
                }
            }
        }
        for n in self.normals.iter_mut() {
            let l = norm(*n);
            if l > 0.0 {
                *n = [n[0] / l, n[1] / l, n[2] / l];
            }
        }
        let (mut h_sum, mut angle_sum, mut count) = (0.0, 0.0, 0usize);
        for i in 0..self.area.len() {
            if !self.interior[i] || self.area[i] <= 0.0 {
                continue;
            }
            h_sum += norm(self.laplace[i]) / (2.0 * self.area[i]);
            let mut mean = [0.0; 3];
            for &j in self.ring.of(i) {
                let nj = self.normals[j as usize];
                mean = [mean[0] + nj[0], mean[1] + nj[1], mean[2] + nj[2]];
            }
            let ni = self.normals[i];
            angle_sum += norm(cross(ni, mean)).atan2(dot(ni, mean));
            count += 1;
        }
        let count = count.max(1) as f64;
        SurfaceQuality {
            mean_abs_h: h_sum / count,
            roughness: angle_sum / count,
        }
    }
}
