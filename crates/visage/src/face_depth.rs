//! Dense "CNN depth" `D_k` of a frame (paper §3, the pipeline's default depth source): the fitted
//! metric FaceMesh surface (468 metric landmarks, 898 triangles; [`face_trimesh`]) rasterised
//! with a z-buffer into a per-pixel depth map and face mask, using `visage-render`'s exact
//! rasteriser (pixel centres, top-left rule, nearest surface wins); and the same for any fitted
//! surface, such as the morphable model's.

use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_face::{face_trimesh, CanonicalMesh, FaceGeometry};
use visage_mesh::TriMesh;

use crate::Error;

/// Renders the depth of every fitted face into one map (nearest face wins), `kind` = z or ray
/// distance, metres, `0` where no face is. The face mask is `DepthMap::is_valid`.
///
/// # Errors
/// A fit the renderer refuses (non-finite vertices), intrinsics beyond its limits.
pub fn render_faces_depth(
    faces: &[FaceGeometry],
    canonical: &CanonicalMesh,
    k: &Intrinsics,
    kind: DepthKind,
) -> Result<DepthMap, Error> {
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
///
/// # Errors
/// An empty mesh, out-of-range indices, non-finite vertices, intrinsics beyond the renderer's
/// limits.
pub fn render_surface_depth(
    mesh: &TriMesh,
    k: &Intrinsics,
    kind: DepthKind,
) -> Result<DepthMap, Error> {
    visage_render::render_depth(mesh, k, None, kind)
        .map(|r| r.depth)
        .map_err(|e| Error::Render {
            reason: e.to_string(),
        })
}
