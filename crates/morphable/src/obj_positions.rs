//! A minimal OBJ reader that keeps the file's vertex numbering: positions and polygons only.
//!
//! `visage_mesh::io::read_obj` appends a copy of a vertex at every UV seam, which would break
//! the one-to-one correspondence between vertex `i` of the neutral mesh and vertex `i` of each
//! mode file that the morphable model relies on. ICT-FaceKit files share positions and
//! topology, so this reader ignores `vt`/`vn` and keeps only the position index of each corner.

use std::path::Path;

use crate::MorphableError;

/// Positions (file units) and polygons (0-based position indices, ≥ 3 corners each) of an OBJ.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjPositions {
    pub positions: Vec<[f64; 3]>,
    /// Empty unless faces were requested.
    pub polygons: Vec<Vec<u32>>,
}

/// Reads the `v` lines of an OBJ file and, with `faces`, its `f` lines (corners `v`, `v/vt`,
/// `v//vn`, `v/vt/vn`, 1-based or negative). Other statements are ignored.
///
/// # Errors
/// Unreadable file, a malformed or non-finite coordinate, a face with fewer than three corners
/// or an index of zero or out of range — named by file and line.
pub fn read_obj_positions(path: &Path, faces: bool) -> Result<ObjPositions, MorphableError> {
    let bytes = std::fs::read(path).map_err(|source| MorphableError::Io {
        path: path.to_owned(),
        source,
    })?;
    let text = String::from_utf8_lossy(&bytes);
    let syntax = |line: usize, reason: String| MorphableError::Syntax {
        path: path.to_owned(),
        line,
        reason,
    };
    let mut out = ObjPositions::default();
    // (line, raw indices) checked once all positions are known (forward references).
    let mut pending: Vec<(usize, Vec<i64>)> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.split('#').next().unwrap_or("");
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            Some("v") => {
                let mut p = [0.0; 3];
                for c in &mut p {
                    let w = words.next().ok_or_else(|| {
                        syntax(line_no, "a vertex needs three coordinates".into())
                    })?;
                    *c = w
                        .parse::<f64>()
                        .map_err(|_| syntax(line_no, format!("{w:?} is not a number")))?;
                    if !c.is_finite() {
                        return Err(syntax(line_no, format!("non-finite coordinate {w:?}")));
                    }
                }
                out.positions.push(p);
            }
            Some("f") if faces => {
                let mut corners = Vec::with_capacity(4);
                for w in words {
                    let first = w.split('/').next().unwrap_or("");
                    let index = first
                        .parse::<i64>()
                        .map_err(|_| syntax(line_no, format!("{w:?} is not a face corner")))?;
                    // Negative indices are relative to the positions defined so far.
                    let index = if index < 0 {
                        out.positions.len() as i64 + index + 1
                    } else {
                        index
                    };
                    corners.push(index);
                }
                if corners.len() < 3 {
                    return Err(syntax(
                        line_no,
                        format!("a face needs 3 corners, got {}", corners.len()),
                    ));
                }
                pending.push((line_no, corners));
            }
            _ => {}
        }
    }
    let n = out.positions.len() as i64;
    out.polygons.reserve(pending.len());
    for (line_no, corners) in pending {
        let mut polygon = Vec::with_capacity(corners.len());
        for c in corners {
            if c < 1 || c > n {
                return Err(syntax(line_no, format!("vertex index {c} outside 1..={n}")));
            }
            polygon.push((c - 1) as u32);
        }
        out.polygons.push(polygon);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(text: &str) -> tempfile::NamedTempFile {
        let f = tempfile::NamedTempFile::new().unwrap();
        std::fs::write(f.path(), text).unwrap();
        f
    }

    #[test]
    fn reads_positions_quads_and_negative_indices_without_seam_copies() {
        let f = write("v 0 0 0\nv 1 0 0\nvt 0 0\nvt 1 1\nv 1 1 0\nv 0 1 0\nf 1/1 2/2 3/1 4/2\nf -4/1 -3/2 -1/1\n");
        let obj = read_obj_positions(f.path(), true).unwrap();
        assert_eq!(obj.positions.len(), 4);
        assert_eq!(obj.polygons, vec![vec![0, 1, 2, 3], vec![0, 1, 3]]);
        let no_faces = read_obj_positions(f.path(), false).unwrap();
        assert!(no_faces.polygons.is_empty());
    }

    #[test]
    fn errors_name_file_and_line() {
        let f = write("v 0 0 0\nv 1 x 0\n");
        let e = read_obj_positions(f.path(), true).unwrap_err().to_string();
        assert!(e.contains(":2:") && e.contains("\"x\""), "{e}");
        let f = write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
        let e = read_obj_positions(f.path(), true).unwrap_err().to_string();
        assert!(e.contains(":4:") && e.contains("index 7"), "{e}");
        let f = write("v 0 0 0\nf 1 1\n");
        assert!(read_obj_positions(f.path(), true).is_err());
        let f = write("v 0 0 inf\n");
        assert!(read_obj_positions(f.path(), true).is_err());
        let missing = std::path::Path::new("/nonexistent/visage/x.obj");
        assert!(read_obj_positions(missing, true)
            .unwrap_err()
            .to_string()
            .contains("x.obj"));
    }
}
