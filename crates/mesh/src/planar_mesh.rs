//! Constrained Delaunay triangulation of the samples on the image plane (paper §4).

use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

use crate::{MeshError, Samples};

/// A triangulation of the image-plane domain Ω.
///
/// - `points` are pixel positions `(u, v)` (x right, y down);
/// - every triangle has **negative** signed area in `(u, v)`, which makes the normal
///   `(v1 − v0) × (v2 − v0)` of the back-projected triangle point toward the camera (−z);
/// - `constraint_edges` are the domain's boundary (never flipped, each on one triangle).
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarMesh {
    pub points: Vec<[f64; 2]>,
    pub triangles: Vec<[u32; 3]>,
    pub constraint_edges: Vec<[u32; 2]>,
}

/// Twice the signed area of triangle `(a, b, c)` (positive when counter-clockwise in a y-up frame).
#[inline]
pub fn orient2d(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

impl PlanarMesh {
    /// Constrained Delaunay triangulation of `samples` with the domain boundary as constraint
    /// edges (spade's bulk loader), keeping the triangles inside the domain.
    pub fn triangulate(samples: &Samples) -> Result<Self, MeshError> {
        let vertices: Vec<Point2<f64>> = samples
            .points
            .iter()
            .map(|p| Point2::new(p[0], p[1]))
            .collect();
        let edges: Vec<[usize; 2]> = samples
            .constraint_edges
            .iter()
            .map(|e| [e[0] as usize, e[1] as usize])
            .collect();
        let cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::bulk_load_cdt(vertices, edges)
            .map_err(|e| MeshError::Triangulation {
            reason: format!("{e:?}"),
        })?;
        if cdt.num_vertices() != samples.points.len() {
            return Err(MeshError::Triangulation {
                reason: format!(
                    "{} duplicate sample points",
                    samples.points.len() - cdt.num_vertices()
                ),
            });
        }
        let mut triangles = Vec::with_capacity(cdt.num_inner_faces());
        for face in cdt.inner_faces() {
            let [a, b, c] = face.vertices().map(|v| v.fix().index() as u32);
            let (pa, pb, pc) = (
                samples.points[a as usize],
                samples.points[b as usize],
                samples.points[c as usize],
            );
            let centroid = [(pa[0] + pb[0] + pc[0]) / 3.0, (pa[1] + pb[1] + pc[1]) / 3.0];
            if !samples.grid.contains(centroid[0], centroid[1]) {
                continue;
            }
            if orient2d(pa, pb, pc) > 0.0 {
                triangles.push([a, c, b]);
            } else {
                triangles.push([a, b, c]);
            }
        }
        Ok(PlanarMesh {
            points: samples.points.clone(),
            triangles,
            constraint_edges: samples.constraint_edges.clone(),
        })
    }

    /// Per vertex: whether it lies on the domain boundary.
    pub fn boundary_vertices(&self) -> Vec<bool> {
        let mut b = vec![false; self.points.len()];
        for e in &self.constraint_edges {
            b[e[0] as usize] = true;
            b[e[1] as usize] = true;
        }
        b
    }

    /// Total area in square pixels.
    pub fn area(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                -0.5 * orient2d(
                    self.points[t[0] as usize],
                    self.points[t[1] as usize],
                    self.points[t[2] as usize],
                )
            })
            .sum()
    }
}
