use std::path::PathBuf;

use visage_camera::CameraError;

/// Errors of the renderer. Every variant carries the offending value, element or file.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The mesh has no vertices or no triangles.
    #[error("the mesh is empty ({vertices} vertices, {triangles} triangles): nothing to render")]
    EmptyMesh { vertices: usize, triangles: usize },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {vertex}, but the mesh has {count} vertices")]
    VertexIndexOutOfRange {
        triangle: usize,
        vertex: u32,
        count: usize,
    },
    /// A vertex position or normal is NaN or infinite.
    #[error("{attribute} of vertex {vertex} is not finite: {value:?}")]
    NonFiniteVertex {
        attribute: &'static str,
        vertex: usize,
        value: [f64; 3],
    },
    /// A per-vertex attribute array has neither zero nor #V entries.
    #[error("the mesh has {len} {attribute} for {vertices} vertices (expected 0 or {vertices})")]
    AttributeLength {
        attribute: &'static str,
        len: usize,
        vertices: usize,
    },
    /// The intrinsics are invalid.
    #[error("degenerate camera: {0}")]
    Camera(#[from] CameraError),
    /// The clipping planes are not `0 < near < far`, both finite.
    #[error("degenerate camera: clipping planes near = {near} m, far = {far} m (need 0 < near < far, finite)")]
    ClipPlanes { near: f64, far: f64 },
    /// A pose or model matrix is not a finite affine map, or its linear part is singular.
    #[error("degenerate {what}: {reason}")]
    Transform { what: &'static str, reason: String },
    /// A material or light parameter violates its documented range (ERRATA 12, Eq. (6.4)).
    #[error("invalid {field} = {value}: {reason}")]
    Parameter {
        field: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// A buffer passed in has another size than the camera's image.
    #[error("{buffer} buffer is {width}×{height} but the camera renders {expected_width}×{expected_height}")]
    BufferSize {
        buffer: &'static str,
        width: u32,
        height: u32,
        expected_width: u32,
        expected_height: u32,
    },
    /// The chosen colour source needs a per-vertex attribute the mesh does not have.
    #[error("{needed_by} needs {attribute}, but the mesh has none")]
    MissingAttribute {
        attribute: &'static str,
        needed_by: &'static str,
    },
    /// A file could not be read, decoded or written.
    #[error("{}: {reason}", path.display())]
    File { path: PathBuf, reason: String },
}
