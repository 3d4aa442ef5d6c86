use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::TriMesh;

/// Errors of mesh reading and writing; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum MeshIoError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Writes `mesh` as binary little-endian PLY: `float x, y, z` per vertex (positions as f32) and
/// `list uchar int vertex_indices` per face.
pub fn write_ply(path: &Path, mesh: &TriMesh) -> Result<(), MeshIoError> {
    let io = |source| MeshIoError::Io {
        path: path.to_owned(),
        source,
    };
    let file = std::fs::File::create(path).map_err(io)?;
    let mut w = BufWriter::new(file);
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment visage\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.vertices.len(),
        mesh.triangles.len()
    )
    .map_err(io)?;
    for v in &mesh.vertices {
        for c in v {
            w.write_all(&(*c as f32).to_le_bytes()).map_err(io)?;
        }
    }
    for t in &mesh.triangles {
        w.write_all(&[3u8]).map_err(io)?;
        for &i in t {
            w.write_all(&(i as i32).to_le_bytes()).map_err(io)?;
        }
    }
    w.flush().map_err(io)
}
