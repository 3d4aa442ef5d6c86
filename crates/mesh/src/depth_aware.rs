//! Depth-aware edge flips (paper §4 "volumetric filter", corrected by ERRATA 9).
//!
//! Starting from the planar constrained Delaunay triangulation, an interior edge is flipped when
//! the Delaunay criterion fails on the **back-projected 3-D triangles** (the two angles opposite
//! the edge sum to more than π) and the flip keeps the image-plane triangulation valid (the
//! quadrilateral is strictly convex in the image). The vertex set is unchanged; the 3-D
//! triangles become better shaped on steep parts of the surface.

use std::collections::HashMap;

use visage_camera::vec3::{cross, dot, norm, sub};

use crate::edge_map::{edge_key, edge_triangles};
use crate::planar_mesh::orient2d;
use crate::{MeshError, PlanarMesh};

/// Flatness ratio (depth range / mean depth) above which `Auto` picks the depth-aware variant.
pub const AUTO_FLATNESS_THRESHOLD: f64 = 0.15;

/// Relative tolerance on the angle sum and on convexity, against flipping back and forth on
/// cocircular or nearly degenerate configurations.
const FLIP_TOLERANCE: f64 = 1e-9;

/// Which triangulation of the samples to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TriangulationKind {
    /// Constrained Delaunay on the image plane.
    Planar,
    /// Planar, then depth-aware flips.
    DepthAware,
    /// Depth-aware when the flatness ratio exceeds [`AUTO_FLATNESS_THRESHOLD`].
    #[default]
    Auto,
}

impl TriangulationKind {
    /// Whether depth-aware flips apply for a scene of this flatness ratio.
    pub fn uses_depth(self, flatness_ratio: f64) -> bool {
        match self {
            TriangulationKind::Planar => false,
            TriangulationKind::DepthAware => true,
            TriangulationKind::Auto => flatness_ratio > AUTO_FLATNESS_THRESHOLD,
        }
    }
}

fn angle_at(c: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let (u, v) = (sub(a, c), sub(b, c));
    norm(cross(u, v)).atan2(dot(u, v))
}

fn opposite(tri: &[u32; 3], a: u32, b: u32) -> u32 {
    tri.iter().copied().find(|&v| v != a && v != b).unwrap_or(a)
}

fn oriented(mesh_points: &[[f64; 2]], t: [u32; 3]) -> [u32; 3] {
    let p = |i: u32| mesh_points[i as usize];
    if orient2d(p(t[0]), p(t[1]), p(t[2])) > 0.0 {
        [t[0], t[2], t[1]]
    } else {
        t
    }
}

/// Applies depth-aware flips to `mesh`, judged on the 3-D `positions` of its vertices
/// (#V × 3, e.g. the back-projected reference depth). Returns the number of flips.
pub fn flip_depth_aware(mesh: &mut PlanarMesh, positions: &[[f64; 3]]) -> Result<usize, MeshError> {
    if positions.len() != mesh.points.len() {
        return Err(MeshError::LengthMismatch {
            what: "3-D positions for depth-aware flips",
            expected: mesh.points.len(),
            got: positions.len(),
        });
    }
    let mut adjacency: HashMap<(u32, u32), Vec<usize>> = edge_triangles(&mesh.triangles);
    let mut stack: Vec<(u32, u32)> = adjacency
        .iter()
        .filter(|(_, t)| t.len() == 2)
        .map(|(&e, _)| e)
        .collect();
    stack.sort_unstable();
    let max_flips = 10 * mesh.triangles.len() + 16;
    let mut flips = 0;
    while let Some((a, b)) = stack.pop() {
        let Some(tris) = adjacency.get(&(a, b)) else {
            continue;
        };
        if tris.len() != 2 {
            continue;
        }
        let (t1, t2) = (tris[0], tris[1]);
        let c = opposite(&mesh.triangles[t1], a, b);
        let d = opposite(&mesh.triangles[t2], a, b);
        let x = |i: u32| positions[i as usize];
        let sum = angle_at(x(c), x(a), x(b)) + angle_at(x(d), x(a), x(b));
        if sum <= std::f64::consts::PI * (1.0 + FLIP_TOLERANCE) {
            continue;
        }
        let p = |i: u32| mesh.points[i as usize];
        let (oa, ob) = (orient2d(p(c), p(d), p(a)), orient2d(p(c), p(d), p(b)));
        let scale = {
            let dx = p(d)[0] - p(c)[0];
            let dy = p(d)[1] - p(c)[1];
            dx * dx + dy * dy
        };
        if !(oa * ob < 0.0
            && oa.abs() > FLIP_TOLERANCE * scale
            && ob.abs() > FLIP_TOLERANCE * scale)
        {
            continue; // the image-plane quadrilateral is not strictly convex
        }
        mesh.triangles[t1] = oriented(&mesh.points, [c, d, a]);
        mesh.triangles[t2] = oriented(&mesh.points, [c, d, b]);
        adjacency.remove(&(a, b));
        adjacency.insert(edge_key(c, d), vec![t1, t2]);
        for (e, from, to) in [((b, c), t1, t2), ((a, d), t2, t1)] {
            if let Some(list) = adjacency.get_mut(&edge_key(e.0, e.1)) {
                for t in list.iter_mut() {
                    if *t == from {
                        *t = to;
                    }
                }
            }
        }
        stack.extend([
            edge_key(a, c),
            edge_key(b, c),
            edge_key(a, d),
            edge_key(b, d),
        ]);
        flips += 1;
        if flips >= max_flips {
            break;
        }
    }
    Ok(flips)
}
