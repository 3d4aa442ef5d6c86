/// An indexed triangle mesh: vertices `V` (#V × 3) and triangles `F` (#F × 3).
///
/// Optional per-vertex attributes have either zero length or #V entries.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex unit normals (empty when absent).
    pub normals: Vec<[f64; 3]>,
    /// Per-vertex texture coordinates in [0, 1]² (empty when absent).
    pub uvs: Vec<[f64; 2]>,
    /// Per-vertex colours, linear RGB in [0, 1] (empty when absent).
    pub colors: Vec<[f32; 3]>,
}

impl TriMesh {
    /// A mesh with positions and triangles only.
    pub fn new(vertices: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>) -> Self {
        TriMesh {
            vertices,
            triangles,
            ..Default::default()
        }
    }
}
