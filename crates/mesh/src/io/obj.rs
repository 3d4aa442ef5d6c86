//! Wavefront OBJ reading and writing.
//!
//! Read: `v x y z [r g b]` (optional sRGB vertex colours), `vt u v [w]`, `vn x y z`, and `f`
//! with corners `v`, `v/vt`, `v//vn` or `v/vt/vn`, 1-based or negative (relative to the
//! elements defined so far). Polygons are split into a fan `(0, i, i+1)`, so quads become two
//! triangles. Other statements (`o`, `g`, `s`, `usemtl`, `mtllib`, `l`, …) are ignored.
//!
//! `TriMesh` stores attributes per vertex while OBJ indexes them per face corner. Vertex `i` of
//! the file stays vertex `i` of the mesh (so blendshapes and landmark indices keep working) and
//! takes the UV/normal of its first corner; a corner that pairs it with a *different* UV or
//! normal (a texture seam) gets a copy of the vertex appended after the file's vertices.
//! UVs (normals) are kept only when every corner has one. [`read_obj_with`] can skip attributes
//! ([`ObjReadOptions::attributes`]): then no seam copies are made and the mesh has exactly the
//! file's vertices, which is what blendshape models (one `v` numbering shared by many files)
//! need.

use std::collections::HashMap;
use std::io::{BufWriter, Write};
use std::path::Path;

use super::MeshIoError;
use crate::color::{linear_to_srgb, srgb_to_linear};
use crate::TriMesh;

/// What [`read_obj_with`] reads; the default reads everything, as [`read_obj`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObjReadOptions {
    /// Read texture coordinates, normals and vertex colours, copying a vertex at every UV or
    /// normal seam (default `true`). With `false` only positions are read: `vt`/`vn` statements,
    /// colours and the texture/normal indices of face corners are skipped, so the mesh has
    /// exactly the file's vertices and every corner keeps its position index.
    pub attributes: bool,
    /// Read the `f` statements (default `true`). With `false` the mesh has no triangles (e.g.
    /// blendshape targets that repeat a topology read from another file).
    pub faces: bool,
}

impl Default for ObjReadOptions {
    fn default() -> Self {
        ObjReadOptions {
            attributes: true,
            faces: true,
        }
    }
}

impl ObjReadOptions {
    /// Positions and faces only: vertex `i` is the `i`-th `v` line, no seam copies.
    pub const POSITIONS_AND_FACES: ObjReadOptions = ObjReadOptions {
        attributes: false,
        faces: true,
    };
    /// Positions only (no faces, no attributes).
    pub const POSITIONS: ObjReadOptions = ObjReadOptions {
        attributes: false,
        faces: false,
    };
}

/// An OBJ file as read by [`read_obj_with`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjMesh {
    /// The mesh (positions in file units).
    pub mesh: TriMesh,
    /// For each triangle of `mesh`, the `f` statement it was fanned from (0-based, file order).
    pub triangle_face: Vec<u32>,
}

/// One face corner: position, UV and normal indices (0-based, resolved).
type Corner = (usize, Option<usize>, Option<usize>);

/// Most values a `v` line may carry (`x y z w r g b` is 7); more are counted, not stored.
const MAX_VALUES: usize = 7;

/// Reads an OBJ mesh: positions, vertex colours, texture coordinates, normals and faces (see the
/// module documentation for seams).
///
/// # Errors
/// Unreadable file; a malformed number, a non-finite coordinate, an index of zero or out of
/// range, a face with fewer than three corners — each named by file and line (1-based).
pub fn read_obj(path: &Path) -> Result<TriMesh, MeshIoError> {
    read_obj_with(path, &ObjReadOptions::default()).map(|obj| obj.mesh)
}

/// Reads an OBJ file with `options` (e.g. [`ObjReadOptions::POSITIONS_AND_FACES`] to keep the
/// file's vertex numbering exactly), and records which `f` statement each triangle came from.
///
/// # Errors
/// As [`read_obj`], for the statements that `options` reads.
pub fn read_obj_with(path: &Path, options: &ObjReadOptions) -> Result<ObjMesh, MeshIoError> {
    let bytes = std::fs::read(path).map_err(|source| MeshIoError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse_obj(&bytes, path, options)
}

/// [`read_obj_with`] of a file's bytes already in memory; `path` is the file they came from,
/// named in errors.
///
/// # Errors
/// As [`read_obj_with`], except that nothing is read from disk.
pub fn parse_obj(
    bytes: &[u8],
    path: &Path,
    options: &ObjReadOptions,
) -> Result<ObjMesh, MeshIoError> {
    let text = String::from_utf8_lossy(bytes);
    let syntax = |line: usize, reason: String| MeshIoError::Syntax {
        path: path.to_owned(),
        line,
        reason,
    };
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut colors: Vec<[f32; 3]> = Vec::new();
    let mut uvs: Vec<[f64; 2]> = Vec::new();
    let mut normals: Vec<[f64; 3]> = Vec::new();
    // Faces, flat: the corners of face k are `corners[face_start[k]..face_start[k + 1]]`;
    // positive indices are checked at the end (forward references).
    let mut corners: Vec<Corner> = Vec::new();
    let mut face_start: Vec<usize> = vec![0];
    let mut face_line: Vec<usize> = Vec::new();
    // Parses the remaining words as numbers into `buf`; returns how many there were.
    let numbers = |words: std::str::SplitAsciiWhitespace<'_>,
                   line_no: usize,
                   buf: &mut [f64; MAX_VALUES]|
     -> Result<usize, MeshIoError> {
        let mut n = 0;
        for w in words {
            let x = w
                .parse::<f64>()
                .map_err(|_| syntax(line_no, format!("{w:?} is not a number")))?;
            if let Some(slot) = buf.get_mut(n) {
                *slot = x;
            }
            n += 1;
        }
        Ok(n)
    };
    let mut buf = [0.0; MAX_VALUES];
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = match raw.find('#') {
            Some(end) => &raw[..end],
            None => raw,
        };
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let n = numbers(words, line_no, &mut buf)?;
                if n != 3 && n != 4 && n != 6 && n != 7 {
                    return Err(syntax(
                        line_no,
                        format!(
                            "a vertex needs 3 coordinates (+ optional w or r g b), found {n} values"
                        ),
                    ));
                }
                let v = &buf[..n];
                if !v.iter().all(|x| x.is_finite()) {
                    return Err(syntax(
                        line_no,
                        format!(
                            "vertex {} has a non-finite coordinate: {v:?}",
                            positions.len() + 1
                        ),
                    ));
                }
                positions.push([v[0], v[1], v[2]]);
                if n >= 6 && options.attributes {
                    let c = &v[n - 3..];
                    colors
                        .push([c[0], c[1], c[2]].map(|x| srgb_to_linear(x.clamp(0.0, 1.0) as f32)));
                }
            }
            "vt" if options.attributes => {
                let n = numbers(words, line_no, &mut buf)?;
                let v = &buf[..n.min(MAX_VALUES)];
                if !(1..=3).contains(&n) || !v.iter().all(|x| x.is_finite()) {
                    return Err(syntax(
                        line_no,
                        format!("a texture coordinate needs 1–3 finite values, found {v:?}"),
                    ));
                }
                uvs.push([v[0], if n > 1 { v[1] } else { 0.0 }]);
            }
            "vn" if options.attributes => {
                let n = numbers(words, line_no, &mut buf)?;
                let v = &buf[..n.min(MAX_VALUES)];
                if n != 3 || !v.iter().all(|x| x.is_finite()) {
                    return Err(syntax(
                        line_no,
                        format!("a normal needs 3 finite values, found {v:?}"),
                    ));
                }
                normals.push([v[0], v[1], v[2]]);
            }
            "f" if options.faces => {
                let first = corners.len();
                for w in words {
                    let mut parts = w.split('/');
                    let mut index = |what: &str,
                                     count: usize,
                                     required: bool|
                     -> Result<Option<usize>, MeshIoError> {
                        match parts.next() {
                            None | Some("") if !required => Ok(None),
                            None | Some("") => {
                                Err(syntax(line_no, format!("corner {w:?} has no {what} index")))
                            }
                            Some(s) => {
                                let k: i64 = s.parse().map_err(|_| {
                                    syntax(line_no, format!("{what} index {s:?} is not an integer"))
                                })?;
                                match k {
                                    0 => Err(syntax(
                                        line_no,
                                        format!(
                                            "{what} index 0 is invalid (OBJ indices start at 1)"
                                        ),
                                    )),
                                    k if k > 0 => Ok(Some(k as usize - 1)),
                                    k => {
                                        let back = k.unsigned_abs() as usize;
                                        if back > count {
                                            Err(syntax(line_no, format!("relative {what} index {k} reaches before the first of the {count} defined so far")))
                                        } else {
                                            Ok(Some(count - back))
                                        }
                                    }
                                }
                            }
                        }
                    };
                    let v = index("vertex", positions.len(), true)?.unwrap_or(0);
                    let (vt, vn) = if options.attributes {
                        (
                            index("texture", uvs.len(), false)?,
                            index("normal", normals.len(), false)?,
                        )
                    } else {
                        (None, None)
                    };
                    corners.push((v, vt, vn));
                }
                let count = corners.len() - first;
                if count < 3 {
                    return Err(syntax(
                        line_no,
                        format!("a face needs 3 or more corners, found {count}"),
                    ));
                }
                face_start.push(corners.len());
                face_line.push(line_no);
            }
            _ => {}
        }
    }
    if !colors.is_empty() && colors.len() != positions.len() {
        // Colours on some vertices only: keep none rather than guess.
        colors.clear();
    }
    let faces = || {
        face_start
            .windows(2)
            .zip(&face_line)
            .map(|(r, &line)| (line, &corners[r[0]..r[1]]))
    };
    for (line, face) in faces() {
        for &(v, vt, vn) in face {
            if v >= positions.len() {
                return Err(syntax(
                    line,
                    format!(
                        "vertex index {} is out of range (the file has {} vertices)",
                        v + 1,
                        positions.len()
                    ),
                ));
            }
            if let Some(t) = vt.filter(|&t| t >= uvs.len()) {
                return Err(syntax(
                    line,
                    format!(
                        "texture index {} is out of range (the file has {} texture coordinates)",
                        t + 1,
                        uvs.len()
                    ),
                ));
            }
            if let Some(n) = vn.filter(|&n| n >= normals.len()) {
                return Err(syntax(
                    line,
                    format!(
                        "normal index {} is out of range (the file has {} normals)",
                        n + 1,
                        normals.len()
                    ),
                ));
            }
        }
    }
    let all_uv = !corners.is_empty() && corners.iter().all(|k| k.1.is_some());
    let all_n = !corners.is_empty() && corners.iter().all(|k| k.2.is_some());

    let nv = positions.len();
    let mut mesh = TriMesh {
        vertices: positions,
        colors,
        ..TriMesh::default()
    };
    if all_uv {
        mesh.uvs = vec![[0.0; 2]; nv];
    }
    if all_n {
        mesh.normals = vec![[0.0; 3]; nv];
    }
    let triangle_count = corners.len() - 2 * face_line.len();
    mesh.triangles.reserve(triangle_count);
    let mut triangle_face = Vec::with_capacity(triangle_count);
    if !all_uv && !all_n {
        // No per-corner attribute is kept, so there are no seams: corners index positions.
        for (f, (_, face)) in faces().enumerate() {
            let v0 = face[0].0 as u32;
            for pair in face[1..].windows(2) {
                mesh.triangles
                    .push([v0, pair[0].0 as u32, pair[1].0 as u32]);
                triangle_face.push(f as u32);
            }
        }
    } else {
        // The (uv, normal) pair each file vertex took first, and seam copies by full key.
        let mut first: Vec<Option<(Option<usize>, Option<usize>)>> = vec![None; nv];
        let mut copies: HashMap<Corner, u32> = HashMap::new();
        let mut idx = Vec::new();
        for (f, (_, face)) in faces().enumerate() {
            idx.clear();
            for &(v, vt, vn) in face {
                let key = (
                    if all_uv { vt } else { None },
                    if all_n { vn } else { None },
                );
                let out = match first[v] {
                    None => {
                        first[v] = Some(key);
                        if let Some(t) = key.0 {
                            mesh.uvs[v] = uvs[t];
                        }
                        if let Some(n) = key.1 {
                            mesh.normals[v] = normals[n];
                        }
                        v as u32
                    }
                    Some(k) if k == key => v as u32,
                    Some(_) => *copies.entry((v, key.0, key.1)).or_insert_with(|| {
                        let new = mesh.vertices.len() as u32;
                        mesh.vertices.push(mesh.vertices[v]);
                        if !mesh.colors.is_empty() {
                            mesh.colors.push(mesh.colors[v]);
                        }
                        if let Some(t) = key.0 {
                            mesh.uvs.push(uvs[t]);
                        }
                        if let Some(n) = key.1 {
                            mesh.normals.push(normals[n]);
                        }
                        new
                    }),
                };
                idx.push(out);
            }
            for i in 1..idx.len() - 1 {
                mesh.triangles.push([idx[0], idx[i], idx[i + 1]]);
                triangle_face.push(f as u32);
            }
        }
    }
    Ok(ObjMesh {
        mesh,
        triangle_face,
    })
}

/// Writes `mesh` as OBJ: `v x y z [r g b]` (sRGB colours when present), `vt` and `vn` per vertex
/// when present, and `f a/a/a b/b/b c/c/c` with one shared index per corner. Numbers use the
/// shortest decimal form that reads back to the same `f64`.
pub fn write_obj(path: &Path, mesh: &TriMesh) -> Result<(), MeshIoError> {
    write_obj_with(path, mesh, None)
}

/// A material an OBJ file refers to: `mtllib LIBRARY` and `usemtl NAME` before the faces.
#[derive(Clone, Copy, Debug)]
pub struct ObjMaterial<'a> {
    /// The `.mtl` file, relative to the OBJ.
    pub library: &'a str,
    /// The material's name in it.
    pub name: &'a str,
}

/// [`write_obj`], with a material for the faces.
pub fn write_obj_with(
    path: &Path,
    mesh: &TriMesh,
    material: Option<ObjMaterial<'_>>,
) -> Result<(), MeshIoError> {
    let nv = mesh.vertices.len();
    for (name, len) in [
        ("normals", mesh.normals.len()),
        ("uvs", mesh.uvs.len()),
        ("colors", mesh.colors.len()),
    ] {
        if len != 0 && len != nv {
            return Err(MeshIoError::Unwritable {
                path: path.to_owned(),
                reason: format!("{len} {name} for {nv} vertices"),
            });
        }
    }
    let io = |source| MeshIoError::Io {
        path: path.to_owned(),
        source,
    };
    let mut w = BufWriter::new(std::fs::File::create(path).map_err(io)?);
    writeln!(
        w,
        "# visage: {} vertices, {} triangles",
        nv,
        mesh.triangles.len()
    )
    .map_err(io)?;
    for (i, v) in mesh.vertices.iter().enumerate() {
        if mesh.colors.is_empty() {
            writeln!(w, "v {} {} {}", v[0], v[1], v[2]).map_err(io)?;
        } else {
            let c = mesh.colors[i].map(linear_to_srgb);
            writeln!(w, "v {} {} {} {} {} {}", v[0], v[1], v[2], c[0], c[1], c[2]).map_err(io)?;
        }
    }
    for t in &mesh.uvs {
        writeln!(w, "vt {} {}", t[0], t[1]).map_err(io)?;
    }
    for n in &mesh.normals {
        writeln!(w, "vn {} {} {}", n[0], n[1], n[2]).map_err(io)?;
    }
    if let Some(m) = material {
        writeln!(w, "mtllib {}\nusemtl {}", m.library, m.name).map_err(io)?;
    }
    let (has_uv, has_n) = (!mesh.uvs.is_empty(), !mesh.normals.is_empty());
    for t in &mesh.triangles {
        let c = t.map(|i| {
            let i = i as u64 + 1;
            match (has_uv, has_n) {
                (false, false) => format!("{i}"),
                (true, false) => format!("{i}/{i}"),
                (false, true) => format!("{i}//{i}"),
                (true, true) => format!("{i}/{i}/{i}"),
            }
        });
        writeln!(w, "f {} {} {}", c[0], c[1], c[2]).map_err(io)?;
    }
    w.flush().map_err(io)
}

/// Writes a one-material `.mtl` file: a matte surface, its diffuse colour from `texture`
/// (a path relative to the `.mtl`) when given, else light grey.
///
/// # Errors
/// The file cannot be written.
pub fn write_mtl(path: &Path, name: &str, texture: Option<&str>) -> Result<(), MeshIoError> {
    let mut text =
        format!("# visage\nnewmtl {name}\nKa 0 0 0\nKd 0.8 0.8 0.8\nKs 0 0 0\nNs 1\nillum 1\n");
    if let Some(t) = texture {
        text.push_str(&format!("map_Kd {t}\n"));
    }
    std::fs::write(path, text).map_err(|source| MeshIoError::Io {
        path: path.to_owned(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quads_slashes_negative_indices_and_seams() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("q.obj");
        let text = "# a quad and a triangle sharing an edge with a UV seam\n\
                    o thing\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nv 2 0 1\n\
                    vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n\
                    usemtl skin\nf 1/1 2/2 3/3 4/4\nf -4/-4 5/5 -3/-3\n";
        std::fs::write(&path, text).unwrap();
        let m = read_obj(&path).unwrap();
        assert_eq!(m.triangles.len(), 3);
        assert_eq!(&m.triangles[..2], &[[0, 1, 2], [0, 2, 3]]);
        // Vertex 2 (1-based) takes UV 2 first, so is kept; vertex 3 in the last face uses UV 3
        // as before. Both share their first (uv) pairing: no seam copies needed here.
        assert_eq!(m.triangles[2], [1, 4, 2]);
        assert_eq!(m.vertices.len(), 5);
        assert_eq!(m.uvs[4], [0.5, 0.5]);
        // Now a seam: vertex 1 with another UV.
        std::fs::write(&path, format!("{text}f 1/5 2/2 5/5\n")).unwrap();
        let m = read_obj(&path).unwrap();
        assert_eq!(m.vertices.len(), 6, "vertex 1 copied for the seam");
        assert_eq!(m.vertices[5], m.vertices[0]);
        assert_eq!(m.uvs[5], [0.5, 0.5]);
        assert_eq!(m.uvs[0], [0.0, 0.0], "the original keeps its first UV");
        assert_eq!(m.triangles[3], [5, 1, 4]);
    }

    #[test]
    fn write_read_round_trip_is_exact() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.obj");
        let mut m = TriMesh::new(
            vec![[0.1, -0.2, 1.0 / 3.0], [1e-9, 0.0, 1.5], [0.0, 1.0, 2.0]],
            vec![[0, 1, 2]],
        );
        m.uvs = vec![[0.25, 0.5], [0.0, 1.0], [1.0, 0.0]];
        m.normals = vec![[0.0, 0.0, -1.0]; 3];
        write_obj(&path, &m).unwrap();
        assert_eq!(read_obj(&path).unwrap(), m);
        m.colors = vec![[0.2, 0.4, 0.6]; 3];
        write_obj(&path, &m).unwrap();
        let back = read_obj(&path).unwrap();
        for (a, b) in back.colors.iter().zip(&m.colors) {
            assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-5), "{a:?} {b:?}");
        }
    }

    #[test]
    fn errors_name_the_file_and_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.obj");
        let cases = [
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
                ":4:",
                "out of range",
            ),
            (
                "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
                ":2:",
                "non-finite",
            ),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", ":4:", "index 0"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n",
                ":4:",
                "before the first",
            ),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", ":4:", "3 or more"),
            ("v 0 0 0\nv 1 0 zero\n", ":2:", "not a number"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
                ":5:",
                "texture index 2",
            ),
            ("v 0 0\n", ":1:", "3 coordinates"),
        ];
        for (text, place, what) in cases {
            std::fs::write(&path, text).unwrap();
            let err = read_obj(&path).unwrap_err().to_string();
            assert!(
                err.contains("bad.obj") && err.contains(place) && err.contains(what),
                "{err}"
            );
        }
        let missing = read_obj(&dir.path().join("none.obj"))
            .unwrap_err()
            .to_string();
        assert!(missing.contains("none.obj"), "{missing}");
    }

    #[test]
    #[cfg_attr(not(shared_data), ignore = "needs ../shared beside the checkout")]
    fn ict_neutral_face_keeps_its_vertex_order() {
        let path = visage_testdata::require(
            visage_testdata::shared_dir()
                .join("data/ict-facekit/FaceXModel/generic_neutral_mesh.obj"),
        );
        let m = read_obj(&path).unwrap();
        assert_eq!(m.triangles.len(), 548 + 2 * 25_836);
        assert!(m.vertices.len() >= 26_719);
        assert_eq!(m.uvs.len(), m.vertices.len());
        assert!(m.normals.is_empty());
        // File vertex 1 is "v 0 -2.48251 11.8387" (centimetres).
        assert_eq!(m.vertices[0], [0.0, -2.48251, 11.8387]);
        // Every appended vertex is a copy of a file vertex (a UV seam).
        let extra = &m.vertices[26_719..];
        assert!(extra.iter().all(|p| m.vertices[..26_719].contains(p)));

        // Positions only: exactly the file's vertices, the same triangles up to seam copies.
        let p = read_obj_with(&path, &ObjReadOptions::POSITIONS_AND_FACES).unwrap();
        assert_eq!(p.mesh.vertices, m.vertices[..26_719]);
        assert!(p.mesh.uvs.is_empty() && p.mesh.normals.is_empty());
        assert_eq!(p.mesh.triangles.len(), m.triangles.len());
        for (a, b) in p.mesh.triangles.iter().zip(&m.triangles) {
            assert_eq!(
                a.map(|i| p.mesh.vertices[i as usize]),
                b.map(|i| m.vertices[i as usize])
            );
        }
        assert_eq!(p.triangle_face.len(), p.mesh.triangles.len());
        assert_eq!(p.triangle_face.last(), Some(&26_383));
    }

    #[test]
    fn positions_only_keeps_the_file_numbering_and_records_faces() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.obj");
        let text = "v 0 0 0 1 0 0\nv 1 0 0 1 0 0\nvt 0 0\nvt 1 1\nv 1 1 0 1 0 0\nv 0 1 0 1 0 0\n\
                    vn 0 0 1\nf 1/1/1 2/2/1 3/1/1 4/2/1\nf -4/2 -3/1 -1/2\n";
        std::fs::write(&path, text).unwrap();
        let full = read_obj_with(&path, &ObjReadOptions::default()).unwrap();
        assert_eq!(full.mesh, read_obj(&path).unwrap());
        assert!(full.mesh.vertices.len() > 4, "seam copies with attributes");
        assert_eq!(full.triangle_face, [0, 0, 1]);

        let p = read_obj_with(&path, &ObjReadOptions::POSITIONS_AND_FACES).unwrap();
        assert_eq!(p.mesh.vertices.len(), 4);
        assert_eq!(p.mesh.triangles, [[0, 1, 2], [0, 2, 3], [0, 1, 3]]);
        assert_eq!(p.triangle_face, [0, 0, 1]);
        assert!(p.mesh.uvs.is_empty() && p.mesh.normals.is_empty() && p.mesh.colors.is_empty());

        let v = read_obj_with(&path, &ObjReadOptions::POSITIONS).unwrap();
        assert_eq!(v.mesh.vertices, p.mesh.vertices);
        assert!(v.mesh.triangles.is_empty() && v.triangle_face.is_empty());

        // Skipped statements are not checked; read ones still are, with file and line.
        std::fs::write(
            &path,
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt x\nf 1/9 2/9 3/9\nf 1 2 5\n",
        )
        .unwrap();
        let e = read_obj_with(&path, &ObjReadOptions::POSITIONS_AND_FACES)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("p.obj:6:") && e.contains("vertex index 5"),
            "{e}"
        );
        assert_eq!(
            read_obj_with(&path, &ObjReadOptions::POSITIONS)
                .unwrap()
                .mesh
                .vertices
                .len(),
            3
        );
        assert!(read_obj(&path).is_err());
    }

    #[test]
    fn a_material_is_named_before_the_faces_and_reads_back() {
        let tmp = tempfile::tempdir().unwrap();
        let mut mesh = TriMesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        );
        mesh.uvs = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let path = tmp.path().join("m.obj");
        let material = ObjMaterial {
            library: "m.mtl",
            name: "face",
        };
        write_obj_with(&path, &mesh, Some(material)).unwrap();
        write_mtl(&tmp.path().join("m.mtl"), "face", Some("texture.png")).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let at = |needle: &str| text.find(needle).unwrap();
        assert!(at("mtllib m.mtl") < at("usemtl face") && at("usemtl face") < at("f 1/1"));
        assert_eq!(read_obj(&path).unwrap(), mesh);
        let mtl = std::fs::read_to_string(tmp.path().join("m.mtl")).unwrap();
        assert!(mtl.contains("newmtl face") && mtl.contains("map_Kd texture.png"));
    }
}
