//! Input checks shared by the render entry points: nothing a user's file contains may panic.

use visage_mesh::TriMesh;

use crate::RenderError;

/// Every position finite.
pub fn check_positions(positions: &[[f64; 3]]) -> Result<(), RenderError> {
    match positions
        .iter()
        .position(|p| !p.iter().all(|x| x.is_finite()))
    {
        Some(vertex) => Err(RenderError::NonFiniteVertex {
            attribute: "position",
            vertex,
            value: positions[vertex],
        }),
        None => Ok(()),
    }
}

/// Every vertex index below `count`.
pub fn check_triangles(triangles: &[[u32; 3]], count: usize) -> Result<(), RenderError> {
    for (triangle, t) in triangles.iter().enumerate() {
        if let Some(&vertex) = t.iter().find(|&&i| i as usize >= count) {
            return Err(RenderError::VertexIndexOutOfRange {
                triangle,
                vertex,
                count,
            });
        }
    }
    Ok(())
}

/// A renderable mesh: non-empty, finite positions and normals, indices in range, attribute
/// arrays of length 0 or #V.
pub fn check_mesh(mesh: &TriMesh) -> Result<(), RenderError> {
    let nv = mesh.vertices.len();
    if nv == 0 || mesh.triangles.is_empty() {
        return Err(RenderError::EmptyMesh {
            vertices: nv,
            triangles: mesh.triangles.len(),
        });
    }
    for (attribute, len) in [
        ("normals", mesh.normals.len()),
        ("uvs", mesh.uvs.len()),
        ("colors", mesh.colors.len()),
    ] {
        if len != 0 && len != nv {
            return Err(RenderError::AttributeLength {
                attribute,
                len,
                vertices: nv,
            });
        }
    }
    check_positions(&mesh.vertices)?;
    if let Some(vertex) = mesh
        .normals
        .iter()
        .position(|n| !n.iter().all(|x| x.is_finite()))
    {
        return Err(RenderError::NonFiniteVertex {
            attribute: "normal",
            vertex,
            value: mesh.normals[vertex],
        });
    }
    check_triangles(&mesh.triangles, nv)
}
