//! Mesh readers and writers (PLY, OBJ and its MTL, PC2 point caches) shared by every stage of visage.
//!
//! Both formats keep positions in the file's units (visage writes metres in camera
//! coordinates); colours in files are sRGB-encoded, in [`crate::TriMesh`] linear ([`crate::color`]). Errors name the
//! file and the offending line (OBJ, PLY header, ASCII PLY) or element (binary PLY); malformed
//! input never panics.

mod error;
mod obj;
mod pc2;
mod ply;

pub use error::MeshIoError;
pub use obj::{
    parse_obj, read_obj, read_obj_with, write_mtl, write_obj, write_obj_with, ObjMaterial, ObjMesh,
    ObjReadOptions,
};
pub use pc2::{parse_pc2, read_pc2, Pc2Writer, PointCache};
pub use ply::{parse_ply, read_ply, write_ply, write_ply_with, PlyFormat, MAX_POLYGON_CORNERS};

use std::path::Path;

/// Reads a mesh by file extension: `.obj` or `.ply` (case-insensitive).
///
/// # Errors
/// As [`read_obj`] / [`read_ply`]; an unknown extension is [`MeshIoError::Format`].
pub fn read_mesh(path: &Path) -> Result<crate::TriMesh, MeshIoError> {
    match extension(path).as_deref() {
        Some("obj") => read_obj(path),
        Some("ply") => read_ply(path),
        other => Err(MeshIoError::Format {
            path: path.to_owned(),
            reason: unknown_format(other),
        }),
    }
}

/// "the name ends in .txt; a mesh is a .obj or .ply file".
fn unknown_format(extension: Option<&str>) -> String {
    match extension {
        Some(e) => format!(
            "not a mesh file visage reads: the name ends in .{e}; a mesh is a .obj or .ply file"
        ),
        None => {
            "not a mesh file visage reads: the name has no extension; a mesh is a .obj or .ply file"
                .to_owned()
        }
    }
}

/// Writes a mesh by file extension: `.obj` or `.ply` (binary little-endian).
pub fn write_mesh(path: &Path, mesh: &crate::TriMesh) -> Result<(), MeshIoError> {
    match extension(path).as_deref() {
        Some("obj") => write_obj(path, mesh),
        Some("ply") => write_ply(path, mesh),
        other => Err(MeshIoError::Unwritable {
            path: path.to_owned(),
            reason: unknown_format(other),
        }),
    }
}

fn extension(path: &Path) -> Option<String> {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
}
