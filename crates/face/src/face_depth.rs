//! Dense "CNN depth" `D_k` of a frame (paper §3, the pipeline's default depth source): the fitted
//! metric FaceMesh surface (468 metric landmarks, 898 triangles) rasterised with a z-buffer into
//! a per-pixel depth map and face mask, using `visage-render`'s exact rasteriser (pixel centres,
//! top-left rule, nearest surface wins).

use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_mesh::TriMesh;

use crate::{CanonicalMesh, FaceError, FaceGeometry};

/// The fitted face as a triangle mesh in camera coordinates (metres): the metric landmarks as
/// vertices, the canonical triangles and UVs.
pub fn face_trimesh(geometry: &FaceGeometry, canonical: &CanonicalMesh) -> TriMesh {
    let mut mesh = TriMesh::new(
        geometry.metric_landmarks.clone(),
        canonical.triangles.clone(),
    );
    mesh.uvs = canonical.uvs.clone();
    mesh
}

/// Renders the depth of every fitted face into one map (nearest face wins), `kind` = z or ray
/// distance, metres, `0` where no face is. The face mask is `DepthMap::is_valid`.
pub fn render_faces_depth(
    faces: &[FaceGeometry],
    canonical: &CanonicalMesh,
    k: &Intrinsics,
    kind: DepthKind,
) -> Result<DepthMap, FaceError> {
    let mut out = DepthMap::empty(k.width, k.height, kind);
    for g in faces {
        let depth = render_surface_depth(&face_trimesh(g, canonical), k, kind)?;
        for (o, &d) in out.data.iter_mut().zip(&depth.data) {
            if DepthMap::is_valid(d) && (!DepthMap::is_valid(*o) || d < *o) {
                *o = d;
            }
        }
    }
    Ok(out)
}

/// Renders the depth of one surface given in camera coordinates (metres; `kind` = z or ray
/// distance, `0` where it is not seen), e.g. the fitted morphable model.
pub fn render_surface_depth(
    mesh: &TriMesh,
    k: &Intrinsics,
    kind: DepthKind,
) -> Result<DepthMap, FaceError> {
    visage_render::render_depth(mesh, k, None, kind)
        .map(|r| r.depth)
        .map_err(|e| FaceError::Render {
            reason: e.to_string(),
        })
}
