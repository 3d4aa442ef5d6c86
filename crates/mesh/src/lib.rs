//! Triangle meshes for visage: the sample-point triangulation of paper §4 (ERRATA 9–10) and
//! mesh I/O shared by every stage.
//!
//! Pipeline: a [`Mask`] of pixels with depth → [`sample_domain`] (grid samples, boundary
//! constraint edges, curvature refinement; [`Samples::add_anchors`] for extra points) →
//! [`PlanarMesh::triangulate`] (constrained Delaunay on the image plane) → optionally
//! [`flip_depth_aware`] (ERRATA 9).
//!
//! Invariants: the planar mesh is fixed for a whole sequence; triangles have negative signed
//! area in pixel coordinates (normals of the back-projected surface face the camera); boundary
//! constraint edges are never flipped.

#![forbid(unsafe_code)]

pub mod color;
mod depth_aware;
mod edge_map;
mod error;
pub mod io;
mod mask;
mod one_ring;
mod planar_mesh;
pub mod point_to_mesh;
mod sampling;
mod trimesh;

pub use depth_aware::{flip_depth_aware, TriangulationKind, AUTO_FLATNESS_THRESHOLD};
pub use edge_map::{edge_key, edge_triangles};
pub use error::MeshError;
pub use mask::Mask;
pub use one_ring::OneRing;
pub use planar_mesh::{orient2d, PlanarMesh};
pub use sampling::{
    sample_domain, CellGrid, Samples, SamplingOptions, ANCHOR_MIN_SEPARATION,
    DEFAULT_REFINE_TOLERANCE_M, MIN_CELL_COVERAGE,
};
pub use trimesh::TriMesh;
