//! The face-anchored mesh (ERRATA 16): vertices defined once on a template face surface — in
//! visage MediaPipe's canonical FaceMesh (468 landmarks, 898 triangles) — so that each vertex is
//! the same point of the face in every frame.
//!
//! A vertex is an [`Anchor`]: a template triangle and barycentric coordinates on it. The domain
//! is the template refined by a regular `n`-fold subdivision of every triangle (its edges cut in
//! `n` equal parts, `n²` sub-triangles), shared edge and corner points merged. The template is
//! already denser where the face has detail — FaceMesh places its landmarks around the eyes,
//! lips and nose several times closer than on the cheeks — and the subdivision keeps those
//! proportions. Connectivity never changes, so the finite-element matrices and their
//! factorisation are built once per clip (the finite-element domain is the template surface
//! itself, see [`crate::AnchoredFuser`]).

use std::collections::HashMap;

use visage_mesh::edge_key;

use crate::FusionError;

/// Largest subdivision factor accepted (factor² sub-triangles per template triangle).
pub const MAX_SUBDIVISION: usize = 16;

/// A point of the template surface: `Σ_j bary[j] · template[triangle[j]]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Anchor {
    /// Index into the template's triangles.
    pub triangle: u32,
    /// Barycentric coordinates (non-negative, summing to 1).
    pub bary: [f64; 3],
}

/// The fixed face-anchored mesh of a clip.
#[derive(Clone, Debug)]
pub struct FaceDomain {
    /// The template's triangles (indices into the template's vertices, e.g. the 468 landmarks).
    pub template_triangles: Vec<[u32; 3]>,
    /// Number of template vertices.
    pub template_vertex_count: usize,
    /// One anchor per domain vertex. The template's own vertices come first, in their order,
    /// so domain vertex `i < template_vertex_count` *is* template vertex `i` (a landmark).
    pub anchors: Vec<Anchor>,
    /// Domain triangles (indices into `anchors`), oriented as their template triangle.
    pub triangles: Vec<[u32; 3]>,
    /// Per domain vertex: whether it lies on the boundary of the surface.
    pub boundary: Vec<bool>,
}

impl FaceDomain {
    /// Refines the template (`vertex_count` vertices, `triangles`) by `factor`-fold
    /// subdivision (`factor = 1` keeps it as it is).
    pub fn subdivide(
        vertex_count: usize,
        triangles: &[[u32; 3]],
        factor: usize,
    ) -> Result<FaceDomain, FusionError> {
        if !(1..=MAX_SUBDIVISION).contains(&factor) {
            return Err(FusionError::InvalidOption {
                name: "subdivision",
                value: factor.to_string(),
                reason: "must be between 1 and 16",
            });
        }
        if triangles.is_empty()
            || triangles
                .iter()
                .flatten()
                .any(|&i| i as usize >= vertex_count)
        {
            return Err(FusionError::InvalidOption {
                name: "template",
                value: format!("{} triangles over {vertex_count} vertices", triangles.len()),
                reason: "needs triangles whose indices name template vertices",
            });
        }
        let n = factor;
        let mut anchors = vec![None; vertex_count];
        // Points on template edges, keyed by (edge, step from the edge's smaller vertex).
        let mut edge_points: HashMap<((u32, u32), usize), u32> = HashMap::new();
        let mut extra: Vec<Anchor> = Vec::new();
        let mut out_triangles = Vec::with_capacity(triangles.len() * n * n);
        // Lattice point (i, j) of a triangle: bary = ((n−i−j)/n, i/n, j/n).
        let mut lattice = vec![0u32; (n + 1) * (n + 1)];
        for (t, tri) in triangles.iter().enumerate() {
            for i in 0..=n {
                for j in 0..=n - i {
                    let bary = [
                        (n - i - j) as f64 / n as f64,
                        i as f64 / n as f64,
                        j as f64 / n as f64,
                    ];
                    let anchor = Anchor {
                        triangle: t as u32,
                        bary,
                    };
                    let id = match (i, j) {
                        (0, 0) => corner(&mut anchors, tri[0], anchor),
                        (i, 0) if i == n => corner(&mut anchors, tri[1], anchor),
                        (0, j) if j == n => corner(&mut anchors, tri[2], anchor),
                        _ => {
                            // Which edge, if any, and the step along it from its first vertex.
                            let on_edge = if j == 0 {
                                Some((tri[0], tri[1], i))
                            } else if i == 0 {
                                Some((tri[0], tri[2], j))
                            } else if i + j == n {
                                Some((tri[1], tri[2], j))
                            } else {
                                None
                            };
                            match on_edge {
                                Some((a, b, step)) => {
                                    let key = edge_key(a, b);
                                    let step = if key.0 == a { step } else { n - step };
                                    *edge_points.entry((key, step)).or_insert_with(|| {
                                        extra.push(anchor);
                                        (vertex_count + extra.len() - 1) as u32
                                    })
                                }
                                None => {
                                    extra.push(anchor);
                                    (vertex_count + extra.len() - 1) as u32
                                }
                            }
                        }
                    };
                    lattice[i * (n + 1) + j] = id;
                }
            }
            let at = |i: usize, j: usize| lattice[i * (n + 1) + j];
            for i in 0..n {
                for j in 0..n - i {
                    out_triangles.push([at(i, j), at(i + 1, j), at(i, j + 1)]);
                    if i + j + 1 < n {
                        out_triangles.push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
                    }
                }
            }
        }
        let Some(anchors) = anchors.into_iter().collect::<Option<Vec<Anchor>>>() else {
            return Err(FusionError::InvalidOption {
                name: "template",
                value: format!("{vertex_count} vertices"),
                reason: "every template vertex must belong to a triangle",
            });
        };
        let mut all = anchors;
        all.extend(extra);
        let boundary = boundary_flags(all.len(), &out_triangles);
        Ok(FaceDomain {
            template_triangles: triangles.to_vec(),
            template_vertex_count: vertex_count,
            anchors: all,
            triangles: out_triangles,
            boundary,
        })
    }

    /// Number of domain vertices.
    pub fn vertex_count(&self) -> usize {
        self.anchors.len()
    }

    /// Interpolates per-template-vertex values (e.g. landmark pixels, canonical positions) at
    /// every domain vertex, into `out` (#V entries).
    ///
    /// # Panics
    /// If `values` does not have one entry per template vertex or `out` one per domain vertex.
    pub fn interpolate<const D: usize>(&self, values: &[[f64; D]], out: &mut [[f64; D]]) {
        assert_eq!(values.len(), self.template_vertex_count);
        assert_eq!(out.len(), self.anchors.len());
        for (o, a) in out.iter_mut().zip(&self.anchors) {
            let t = self.template_triangles[a.triangle as usize];
            *o =
                std::array::from_fn(|d| (0..3).map(|c| a.bary[c] * values[t[c] as usize][d]).sum());
        }
    }
}

fn corner(anchors: &mut [Option<Anchor>], vertex: u32, anchor: Anchor) -> u32 {
    let slot = &mut anchors[vertex as usize];
    if slot.is_none() {
        *slot = Some(anchor);
    }
    vertex
}

/// Vertices on an edge used by exactly one triangle.
fn boundary_flags(vertex_count: usize, triangles: &[[u32; 3]]) -> Vec<bool> {
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in triangles {
        for k in 0..3 {
            *uses.entry(edge_key(t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    let mut boundary = vec![false; vertex_count];
    for ((a, b), count) in uses {
        if count == 1 {
            boundary[a as usize] = true;
            boundary[b as usize] = true;
        }
    }
    boundary
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles sharing an edge (a unit square).
    fn square() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        (
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn subdivision_merges_shared_points_and_keeps_the_template_first() {
        let (v, t) = square();
        for n in 1..=5 {
            let d = FaceDomain::subdivide(v.len(), &t, n).unwrap();
            // A square cut into an n × n grid of points along each side: (n+1)² vertices.
            assert_eq!(d.vertex_count(), (n + 1) * (n + 1), "n = {n}");
            assert_eq!(d.triangles.len(), 2 * n * n);
            let mut pos = vec![[0.0; 3]; d.vertex_count()];
            d.interpolate(&v, &mut pos);
            for i in 0..v.len() {
                assert_eq!(pos[i], v[i]);
            }
            // Every point distinct; orientation preserved (template triangles have +z normal).
            for i in 0..pos.len() {
                for j in i + 1..pos.len() {
                    let d2: f64 = (0..3).map(|a| (pos[i][a] - pos[j][a]).powi(2)).sum();
                    assert!(d2 > 1e-12, "duplicate point {i} {j}");
                }
            }
            for tri in &d.triangles {
                let [a, b, c] = tri.map(|i| pos[i as usize]);
                let z = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
                assert!(z > 0.0);
            }
            let on_boundary = d.boundary.iter().filter(|&&b| b).count();
            assert_eq!(on_boundary, 4 * n);
        }
    }

    #[test]
    fn bad_templates_are_refused() {
        let (v, t) = square();
        assert!(FaceDomain::subdivide(v.len(), &t, 0).is_err());
        assert!(FaceDomain::subdivide(v.len(), &t, 17).is_err());
        assert!(FaceDomain::subdivide(2, &t, 1).is_err());
        assert!(FaceDomain::subdivide(5, &t, 1).is_err());
    }
}
