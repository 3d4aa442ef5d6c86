//! Reading a run's surfaces back: sample `k` of the point cache (`sequence.pc2`) on the
//! `mesh.obj` beside it, in camera coordinates again.

use std::path::Path;

use visage_mesh::io::{read_mesh, read_obj, read_pc2};
use visage_mesh::TriMesh;

use crate::error::RunFolderError;
use crate::file_names::CACHE_MESH;
use crate::output::camera_to_y_up;

/// A mesh file (`.obj`, `.ply`), or sample `frame` of a run's point cache (`.pc2`) on the
/// `mesh.obj` beside it, back in camera coordinates (metres, x right, y down; the files'
/// y-up axes are a half turn about x from them) and without normals. `frame` must be given
/// for a point cache and only for one; the messages name the command line's `--frame`.
///
/// # Errors
/// [`RunFolderError::FrameWithoutCache`], [`RunFolderError::CacheWithoutFrame`],
/// [`RunFolderError::CacheMeshMismatch`] (the cache's points are not the mesh's vertices),
/// [`RunFolderError::CacheFrameOutOfRange`], or [`RunFolderError::ReadMesh`] when a file
/// cannot be read.
pub fn read_mesh_or_cache(path: &Path, frame: Option<usize>) -> Result<TriMesh, RunFolderError> {
    let is_cache = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pc2"));
    match (is_cache, frame) {
        (false, None) => Ok(read_mesh(path)?),
        (false, Some(_)) => Err(RunFolderError::FrameWithoutCache {
            path: path.to_owned(),
        }),
        (true, None) => Err(RunFolderError::CacheWithoutFrame {
            path: path.to_owned(),
        }),
        (true, Some(frame)) => read_cache_sample(path, frame),
    }
}

/// Sample `frame` of the point cache `cache` on the `mesh.obj` beside it, in camera
/// coordinates and without normals (see [`read_mesh_or_cache`]).
///
/// # Errors
/// As [`read_mesh_or_cache`] for a point cache.
pub fn read_cache_sample(cache: &Path, frame: usize) -> Result<TriMesh, RunFolderError> {
    let samples = read_pc2(cache)?;
    let obj = cache.with_file_name(CACHE_MESH);
    let mut mesh = read_obj(&obj)?;
    if samples.points != mesh.vertices.len() {
        return Err(RunFolderError::CacheMeshMismatch {
            cache: cache.to_owned(),
            points: samples.points,
            mesh: obj,
            vertices: mesh.vertices.len(),
        });
    }
    if frame >= samples.samples() {
        return Err(RunFolderError::CacheFrameOutOfRange {
            cache: cache.to_owned(),
            frame,
            samples: samples.samples(),
        });
    }
    mesh.vertices = samples
        .sample(frame)
        .chunks_exact(3)
        .map(|p| camera_to_y_up([p[0] as f64, p[1] as f64, p[2] as f64]))
        .collect();
    mesh.normals.clear();
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use visage_mesh::io::{write_obj, Pc2Writer};

    use super::*;

    /// A run folder with a one-triangle `mesh.obj` and a two-sample cache (y-up, as a run
    /// writes them).
    fn folder() -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        let mesh = TriMesh {
            vertices: vec![[0.0, 0.0, -0.5], [0.1, 0.0, -0.5], [0.0, 0.1, -0.5]],
            triangles: vec![[0, 1, 2]],
            ..TriMesh::default()
        };
        write_obj(&dir.path().join(CACHE_MESH), &mesh).unwrap();
        let mut cache = Pc2Writer::create(&dir.path().join("sequence.pc2"), 3, 0.0).unwrap();
        cache.push(&mesh.vertices).unwrap();
        let moved: Vec<[f64; 3]> = mesh
            .vertices
            .iter()
            .map(|p| [p[0], p[1] + 0.25, p[2]])
            .collect();
        cache.push(&moved).unwrap();
        cache.finish().unwrap();
        dir
    }

    #[test]
    fn a_sample_comes_back_in_camera_coordinates() {
        let dir = folder();
        let mesh = read_mesh_or_cache(&dir.path().join("sequence.pc2"), Some(1)).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
        // y-up (0, 0.25, −0.5) → camera (0, −0.25, 0.5), exact in f32.
        assert_eq!(mesh.vertices[0], [0.0, -0.25, 0.5]);
        assert!(mesh.normals.is_empty());
    }

    #[test]
    fn frame_and_cache_go_together() {
        let dir = folder();
        let cache = dir.path().join("sequence.pc2");
        let obj = dir.path().join(CACHE_MESH);
        let message = |r: Result<TriMesh, RunFolderError>| r.unwrap_err().to_string();
        assert_eq!(
            message(read_mesh_or_cache(&obj, Some(0))),
            format!(
                "--frame needs a point cache (OUT/sequence.pc2), not {}",
                obj.display()
            )
        );
        assert_eq!(
            message(read_mesh_or_cache(&cache, None)),
            format!(
                "{}: a point cache needs --frame N (the sample to render)",
                cache.display()
            )
        );
        assert_eq!(
            message(read_mesh_or_cache(&cache, Some(2))),
            format!("{}: --frame 2: the cache has 2 samples", cache.display())
        );
        assert_eq!(read_mesh_or_cache(&obj, None).unwrap().vertices.len(), 3);
    }
}
