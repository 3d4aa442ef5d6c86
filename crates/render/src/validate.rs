//! Input checks shared by the render entry points: nothing a user's file contains may panic.
//!
//! The per-vertex and per-triangle checks run in parallel (rayon) and report the first offending
//! element, as a serial scan would.

use rayon::prelude::*;
use visage_mesh::TriMesh;

use crate::mat4::Mat4;
use crate::RenderError;

/// Elements per parallel task of a check.
const CHECK_CHUNK: usize = 8192;

/// The index of the first element of `items` that is `bad`: chunks are scanned in parallel,
/// then the first bad chunk serially.
fn position_first<T: Sync>(items: &[T], bad: impl Fn(&T) -> bool + Sync) -> Option<usize> {
    let chunk = items
        .par_chunks(CHECK_CHUNK)
        .position_first(|c| c.iter().any(&bad))?;
    let start = chunk * CHECK_CHUNK;
    Some(start + items[start..].iter().position(bad)?)
}

/// The index of the first point with a non-finite coordinate.
fn first_non_finite(points: &[[f64; 3]]) -> Option<usize> {
    position_first(points, |p| !p.iter().all(|x| x.is_finite()))
}

/// Every position finite.
pub fn check_positions(positions: &[[f64; 3]]) -> Result<(), RenderError> {
    match first_non_finite(positions) {
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
    let out_of_range = |t: &[u32; 3]| t.iter().copied().find(|&i| i as usize >= count);
    match position_first(triangles, |t| out_of_range(t).is_some())
        .and_then(|triangle| Some((triangle, out_of_range(&triangles[triangle])?)))
    {
        Some((triangle, vertex)) => Err(RenderError::VertexIndexOutOfRange {
            triangle,
            vertex,
            count,
        }),
        None => Ok(()),
    }
}

/// A model matrix `M` (Eq. (6.1)) that is affine with finite entries.
pub fn check_model(model: &Mat4) -> Result<(), RenderError> {
    if model.is_finite_affine() {
        Ok(())
    } else {
        Err(RenderError::Transform {
            what: "model matrix",
            reason: format!("not a finite affine matrix: {model:?}"),
        })
    }
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
    if let Some(vertex) = first_non_finite(&mesh.normals) {
        return Err(RenderError::NonFiniteVertex {
            attribute: "normal",
            vertex,
            value: mesh.normals[vertex],
        });
    }
    check_triangles(&mesh.triangles, nv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_offending_element_is_reported_whatever_the_split() {
        // Long enough for several parallel tasks, with a later offender in an earlier task's
        // shadow: the first one must win.
        let mut positions = vec![[0.5; 3]; 50_000];
        positions[41_000][1] = f64::NAN;
        positions[9_001][2] = f64::INFINITY;
        assert!(matches!(
            check_positions(&positions),
            Err(RenderError::NonFiniteVertex { vertex: 9_001, .. })
        ));
        let mut triangles = vec![[0, 1, 2]; 50_000];
        triangles[45_000] = [0, 99, 1];
        triangles[12_345] = [3, 70_000, 60_000];
        assert!(matches!(
            check_triangles(&triangles, 100),
            Err(RenderError::VertexIndexOutOfRange {
                triangle: 12_345,
                vertex: 70_000,
                count: 100
            })
        ));
        assert!(check_triangles(&triangles[..12_345], 100).is_ok());
        assert!(check_positions(&positions[..9_001]).is_ok());
    }
}
