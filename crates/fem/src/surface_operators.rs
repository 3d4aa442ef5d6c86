//! Discrete differential geometry of a triangulated surface in 3-D (paper §5, Meyer et al.
//! 2003): mixed Voronoi areas, the mean-curvature normal and mean curvature, area-weighted
//! vertex normals and Gaussian curvature by angle defect — per vertex, on any triangle mesh.
//!
//! The cotangent Laplacian itself is [`crate::cotan_laplacian`] (with `D = 3`; positive
//! semi-definite, the sign opposite to libigl's `cotmatrix`).
//!
//! **Mixed areas** (Meyer et al., Fig. 4): a vertex of a non-obtuse triangle gets its Voronoi
//! share `⅛ Σ (cot α |e|²)` over the two incident edges; in an obtuse triangle the obtuse
//! corner gets half the triangle's area and the other two a quarter each. They tile the
//! surface: the areas sum to the mesh's area (libigl `massmatrix(…, MASSMATRIX_TYPE_VORONOI)`).
//!
//! **Boundary vertices**: their one-ring is open, so `(L x)_i` measures the boundary's own
//! bend (the natural-boundary flux), not the surface's; their mean curvature is reported as
//! NaN and the Gaussian curvature uses the boundary defect `π − Σθ` (geodesic curvature of the
//! boundary), so that Σ K_i A-free angle defects satisfy Gauss–Bonnet (`Σ defects = 2πχ`).

use crate::triangle::{cross_norm, dot, sub};

/// The per-vertex geometry of a surface.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceGeometry {
    /// Mixed Voronoi area per vertex (m²).
    pub area: Vec<f64>,
    /// Mean-curvature normal `H_i n_i = (L x)_i / (2 A_i)`, `(L x)_i = Σ_j w_ij (x_i − x_j)`
    /// (1/m; it points away from the centre of a sphere, length 1/r); NaN at boundary
    /// vertices.
    pub mean_curvature_normal: Vec<[f64; 3]>,
    /// Unsigned mean curvature `|H_i|` (1/m); NaN at boundary vertices.
    pub mean_curvature: Vec<f64>,
    /// Area-weighted unit vertex normals (following the triangles' orientation).
    pub normals: Vec<[f64; 3]>,
    /// Angle defect: `2π − Σθ` inside, `π − Σθ` on the boundary (radians; Gaussian curvature
    /// is `defect / A_i`).
    pub angle_defect: Vec<f64>,
    /// Whether each vertex lies on the boundary (an edge with one triangle).
    pub boundary: Vec<bool>,
}

impl SurfaceGeometry {
    /// Gaussian curvature `K_i = defect_i / A_i` (1/m²).
    pub fn gaussian_curvature(&self) -> Vec<f64> {
        self.angle_defect
            .iter()
            .zip(&self.area)
            .map(|(d, a)| if *a > 0.0 { d / a } else { f64::NAN })
            .collect()
    }
}

/// The boundary vertices: those on an edge that only one triangle uses.
pub fn boundary_vertices(vertex_count: usize, triangles: &[[u32; 3]]) -> Vec<bool> {
    let mut edges = std::collections::HashMap::with_capacity(3 * triangles.len());
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0u32) += 1;
        }
    }
    let mut boundary = vec![false; vertex_count];
    for ((a, b), count) in edges {
        if count == 1 {
            boundary[a as usize] = true;
            boundary[b as usize] = true;
        }
    }
    boundary
}

/// Mixed Voronoi areas (Meyer et al.'s rule for obtuse triangles) of every vertex.
pub fn mixed_areas(points: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<f64> {
    let mut area = vec![0.0; points.len()];
    for t in triangles {
        let p = t.map(|i| points[i as usize]);
        let double_area = cross_norm(&sub(p[1], p[0]), &sub(p[2], p[0]));
        if double_area <= 0.0 {
            continue;
        }
        let tri_area = 0.5 * double_area;
        // cot of the angle at each corner, and whether it is obtuse.
        let cot: [f64; 3] = std::array::from_fn(|k| {
            let (ei, ej) = (sub(p[(k + 1) % 3], p[k]), sub(p[(k + 2) % 3], p[k]));
            dot(&ei, &ej) / double_area
        });
        let obtuse = cot.iter().position(|&c| c < 0.0);
        for k in 0..3 {
            area[t[k] as usize] += match obtuse {
                Some(o) if o == k => 0.5 * tri_area,
                Some(_) => 0.25 * tri_area,
                None => {
                    // ⅛ (cot at the corner opposite each incident edge) |edge|².
                    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
                    let e_ki = sub(p[i], p[k]);
                    let e_kj = sub(p[j], p[k]);
                    0.125 * (cot[j] * dot(&e_ki, &e_ki) + cot[i] * dot(&e_kj, &e_kj))
                }
            };
        }
    }
    area
}

/// Every per-vertex quantity of the surface `points`, `triangles`.
pub fn surface_geometry(points: &[[f64; 3]], triangles: &[[u32; 3]]) -> SurfaceGeometry {
    let n = points.len();
    let boundary = boundary_vertices(n, triangles);
    let area = mixed_areas(points, triangles);
    let mut laplace = vec![[0.0; 3]; n];
    let mut normals = vec![[0.0; 3]; n];
    let mut angles = vec![0.0; n];
    for t in triangles {
        let p = t.map(|i| points[i as usize]);
        let (u, v) = (sub(p[1], p[0]), sub(p[2], p[0]));
        let face_normal = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let double_area = cross_norm(&u, &v);
        if double_area <= 0.0 {
            continue;
        }
        for k in 0..3 {
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            let (ei, ej) = (sub(p[i], p[k]), sub(p[j], p[k]));
            // The edge ij's weight from this triangle: ½ cot of the angle at k.
            let half_cot = 0.5 * dot(&ei, &ej) / double_area;
            let d = sub(p[i], p[j]);
            for c in 0..3 {
                laplace[t[i] as usize][c] += half_cot * d[c];
                laplace[t[j] as usize][c] -= half_cot * d[c];
            }
            angles[t[k] as usize] += double_area.atan2(dot(&ei, &ej));
            let corner = &mut normals[t[k] as usize];
            for c in 0..3 {
                corner[c] += face_normal[c];
            }
        }
    }
    let normals: Vec<[f64; 3]> = normals
        .iter()
        .map(|m| {
            let l = dot(m, m).sqrt();
            if l > 0.0 {
                m.map(|c| c / l)
            } else {
                [0.0; 3]
            }
        })
        .collect();
    let mean_curvature_normal: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            if boundary[i] || area[i] <= 0.0 {
                [f64::NAN; 3]
            } else {
                // Meyer et al.: K(x_i) = (L x)_i / A_i = 2 H n.
                laplace[i].map(|c| c / (2.0 * area[i]))
            }
        })
        .collect();
    let mean_curvature = mean_curvature_normal
        .iter()
        .map(|h| dot(h, h).sqrt())
        .collect();
    let angle_defect = (0..n)
        .map(|i| {
            let full = if boundary[i] {
                std::f64::consts::PI
            } else {
                std::f64::consts::TAU
            };
            full - angles[i]
        })
        .collect();
    SurfaceGeometry {
        area,
        mean_curvature_normal,
        mean_curvature,
        normals,
        angle_defect,
        boundary,
    }
}

#[cfg(test)]
/// An icosahedron subdivided `levels` times, projected onto the sphere of radius `r`.
pub(crate) fn icosphere(levels: usize, r: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<[f64; 3]> = vec![
        [-1.0, g, 0.0],
        [1.0, g, 0.0],
        [-1.0, -g, 0.0],
        [1.0, -g, 0.0],
        [0.0, -1.0, g],
        [0.0, 1.0, g],
        [0.0, -1.0, -g],
        [0.0, 1.0, -g],
        [g, 0.0, -1.0],
        [g, 0.0, 1.0],
        [-g, 0.0, -1.0],
        [-g, 0.0, 1.0],
    ];
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::with_capacity(4 * f.len());
        for t in &f {
            let m: [u32; 3] = std::array::from_fn(|k| {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let (p, q) = (v[a as usize], v[b as usize]);
                    v.push(std::array::from_fn(|c| 0.5 * (p[c] + q[c])));
                    (v.len() - 1) as u32
                })
            });
            next.extend([
                [t[0], m[0], m[2]],
                [t[1], m[1], m[0]],
                [t[2], m[2], m[1]],
                [m[0], m[1], m[2]],
            ]);
        }
        f = next;
    }
    for p in &mut v {
        let l = dot(p, p).sqrt();
        *p = p.map(|c| r * c / l);
    }
    (v, f)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn surface_area(points: &[[f64; 3]], triangles: &[[u32; 3]]) -> f64 {
        triangles
            .iter()
            .map(|t| {
                let p = t.map(|i| points[i as usize]);
                0.5 * cross_norm(&sub(p[1], p[0]), &sub(p[2], p[0]))
            })
            .sum()
    }

    #[test]
    fn a_sphere_has_mean_curvature_one_over_r_closer_under_refinement() {
        let r = 0.08;
        let mut errors = Vec::new();
        // From level 2 on (level 1 is exact by symmetry).
        for levels in 2..5 {
            let (v, f) = icosphere(levels, r);
            let g = surface_geometry(&v, &f);
            assert!(g.boundary.iter().all(|b| !b));
            let worst = g
                .mean_curvature
                .iter()
                .map(|h| (h * r - 1.0).abs())
                .fold(0.0, f64::max);
            errors.push(worst);
            // The mean-curvature normal points away from the centre.
            let (p, h) = (v[7], g.mean_curvature_normal[7]);
            assert!(dot(&p, &h) > 0.0);
            // Gauss–Bonnet on a closed sphere, and the areas tile it.
            let defects: f64 = g.angle_defect.iter().sum();
            assert!(
                (defects - 2.0 * std::f64::consts::TAU).abs() < 1e-9,
                "{defects}"
            );
            let total: f64 = g.area.iter().sum();
            assert!((total - surface_area(&v, &f)).abs() < 1e-12 * total.max(1.0));
        }
        assert!(errors[2] < errors[1] && errors[1] < errors[0], "{errors:?}");
        // The run's figures use the same operators: mean |H| is these curvatures' mean.
        let (v, f) = icosphere(3, r);
        let g = surface_geometry(&v, &f);
        let mean = g.mean_curvature.iter().sum::<f64>() / v.len() as f64;
        let mut metrics = crate::SurfaceMetrics::new(v.len(), &f, &g.boundary);
        let figures = metrics.evaluate(&v);
        assert!(
            (figures.mean_abs_h - mean).abs() < 1e-9 * mean,
            "{figures:?} vs {mean}"
        );
        assert!(errors[2] < 1e-5, "{errors:?}");
    }

    #[test]
    fn a_bent_sheet_with_obtuse_triangles_keeps_its_area_and_a_plane_is_flat() {
        // A 5 × 4 grid with sheared, partly obtuse triangles, flat, then bent about y.
        let (nx, ny) = (5usize, 4usize);
        let flat: Vec<[f64; 3]> = (0..ny)
            .flat_map(|j| {
                (0..nx).map(move |i| {
                    let shear = if j % 2 == 1 { 0.45 } else { 0.0 };
                    [i as f64 + shear, 0.6 * j as f64, 0.0]
                })
            })
            .collect();
        let mut f = Vec::new();
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let a = (j * nx + i) as u32;
                let (b, c, d) = (a + 1, a + nx as u32, a + nx as u32 + 1);
                f.push([a, b, d]);
                f.push([a, d, c]);
            }
        }
        let g = surface_geometry(&flat, &f);
        let interior: Vec<usize> = (0..flat.len()).filter(|&i| !g.boundary[i]).collect();
        assert_eq!(interior.len(), (nx - 2) * (ny - 2));
        for &i in &interior {
            assert!(g.mean_curvature[i] < 1e-12, "{}", g.mean_curvature[i]);
            assert!(g.angle_defect[i].abs() < 1e-12);
            assert!((g.normals[i][2].abs() - 1.0).abs() < 1e-12);
        }
        assert!(g.mean_curvature[0].is_nan(), "boundary: no mean curvature");
        let bent: Vec<[f64; 3]> = flat
            .iter()
            .map(|p| {
                let a = p[0] / 4.0;
                [4.0 * a.sin(), p[1], 4.0 * (1.0 - a.cos())]
            })
            .collect();
        for points in [&flat, &bent] {
            let total: f64 = mixed_areas(points, &f).iter().sum();
            let area = surface_area(points, &f);
            assert!((total - area).abs() < 1e-12 * area, "{total} vs {area}");
        }
        // Gauss–Bonnet on a disc: the defects sum to 2π.
        let defects: f64 = surface_geometry(&bent, &f).angle_defect.iter().sum();
        assert!((defects - std::f64::consts::TAU).abs() < 1e-9, "{defects}");
    }
}
