//! PLY (Stanford polygon format): ASCII and binary (little- and big-endian) reading; binary
//! little-endian and ASCII writing.
//!
//! Vertex properties understood: `x y z` (positions), `nx ny nz` (normals), `s t` / `u v` /
//! `texture_u texture_v` / `texture_s texture_t` (texture coordinates, v up), `red green blue`
//! (colours: integer types are 8-bit sRGB, float types sRGB in [0, 1]; stored linear in
//! [`TriMesh::colors`]). Faces: a `vertex_indices` or `vertex_index` list; polygons with more than
//! three corners are split into a fan `(0, i, i+1)`. Other elements and properties are skipped.

use std::io::{BufWriter, Write};
use std::path::Path;

use super::MeshIoError;
use crate::color::{linear_to_srgb_u8, srgb_to_linear};
use crate::TriMesh;

/// Encoding of a PLY file to write.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PlyFormat {
    /// `binary_little_endian 1.0` (compact, exact for `f32`).
    #[default]
    BinaryLittleEndian,
    /// `ascii 1.0` (human-readable; shortest decimal that round-trips each value).
    Ascii,
}

/// Largest polygon accepted in a face list: a guard against corrupt counts.
pub const MAX_POLYGON_CORNERS: usize = 1 << 16;

/// Writes `mesh` as binary little-endian PLY: `float x y z` per vertex (positions as `f32`),
/// `float nx ny nz` when normals are present, `float s t` for UVs, `uchar red green blue`
/// (sRGB) for colours, and `list uchar int vertex_indices` per face.
pub fn write_ply(path: &Path, mesh: &TriMesh) -> Result<(), MeshIoError> {
    write_ply_with(path, mesh, PlyFormat::BinaryLittleEndian)
}

/// Writes `mesh` as PLY in the given encoding (properties as in [`write_ply`]).
///
/// # Errors
/// An attribute array whose length is neither 0 nor #V, a vertex index beyond `i32::MAX`, or an
/// I/O failure; all name the file.
pub fn write_ply_with(path: &Path, mesh: &TriMesh, format: PlyFormat) -> Result<(), MeshIoError> {
    let nv = mesh.vertices.len();
    let unwritable = |reason: String| MeshIoError::Unwritable {
        path: path.to_owned(),
        reason,
    };
    for (name, len) in [
        ("normals", mesh.normals.len()),
        ("uvs", mesh.uvs.len()),
        ("colors", mesh.colors.len()),
    ] {
        if len != 0 && len != nv {
            return Err(unwritable(format!("{len} {name} for {nv} vertices")));
        }
    }
    if nv > i32::MAX as usize {
        return Err(unwritable(format!(
            "{nv} vertices exceed PLY's int indices"
        )));
    }
    let io = |source| MeshIoError::Io {
        path: path.to_owned(),
        source,
    };
    let file = std::fs::File::create(path).map_err(io)?;
    let mut w = BufWriter::new(file);
    let fmt = match format {
        PlyFormat::BinaryLittleEndian => "binary_little_endian",
        PlyFormat::Ascii => "ascii",
    };
    let mut header = format!("ply\nformat {fmt} 1.0\ncomment visage\nelement vertex {nv}\n");
    header += "property float x\nproperty float y\nproperty float z\n";
    let (has_n, has_uv, has_c) = (
        !mesh.normals.is_empty(),
        !mesh.uvs.is_empty(),
        !mesh.colors.is_empty(),
    );
    if has_n {
        header += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    if has_uv {
        header += "property float s\nproperty float t\n";
    }
    if has_c {
        header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    }
    header += &format!(
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.triangles.len()
    );
    w.write_all(header.as_bytes()).map_err(io)?;
    match format {
        PlyFormat::BinaryLittleEndian => {
            for i in 0..nv {
                let mut floats: Vec<f32> = mesh.vertices[i].iter().map(|&c| c as f32).collect();
                if has_n {
                    floats.extend(mesh.normals[i].iter().map(|&c| c as f32));
                }
                if has_uv {
                    floats.extend(mesh.uvs[i].iter().map(|&c| c as f32));
                }
                for f in floats {
                    w.write_all(&f.to_le_bytes()).map_err(io)?;
                }
                if has_c {
                    w.write_all(&mesh.colors[i].map(linear_to_srgb_u8))
                        .map_err(io)?;
                }
            }
            for t in &mesh.triangles {
                w.write_all(&[3u8]).map_err(io)?;
                for &i in t {
                    w.write_all(&(i as i32).to_le_bytes()).map_err(io)?;
                }
            }
        }
        PlyFormat::Ascii => {
            for i in 0..nv {
                let mut line = mesh.vertices[i].map(|c| (c as f32).to_string()).join(" ");
                if has_n {
                    line += &format!(
                        " {}",
                        mesh.normals[i].map(|c| (c as f32).to_string()).join(" ")
                    );
                }
                if has_uv {
                    line += &format!(" {}", mesh.uvs[i].map(|c| (c as f32).to_string()).join(" "));
                }
                if has_c {
                    line += &format!(
                        " {}",
                        mesh.colors[i]
                            .map(|c| linear_to_srgb_u8(c).to_string())
                            .join(" ")
                    );
                }
                writeln!(w, "{line}").map_err(io)?;
            }
            for t in &mesh.triangles {
                writeln!(w, "3 {} {} {}", t[0], t[1], t[2]).map_err(io)?;
            }
        }
    }
    w.flush().map_err(io)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    fn decode(self, b: &[u8], big_endian: bool) -> f64 {
        macro_rules! num {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                (if big_endian {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }) as f64
            }};
        }
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => num!(i16, 2),
            Scalar::U16 => num!(u16, 2),
            Scalar::I32 => num!(i32, 4),
            Scalar::U32 => num!(u32, 4),
            Scalar::F32 => num!(f32, 4),
            Scalar::F64 => num!(f64, 8),
        }
    }
}

#[derive(Clone, Debug)]
enum Property {
    Scalar {
        name: String,
        ty: Scalar,
    },
    List {
        name: String,
        count: Scalar,
        item: Scalar,
    },
}

impl Property {
    fn name(&self) -> &str {
        match self {
            Property::Scalar { name, .. } | Property::List { name, .. } => name,
        }
    }
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    Binary { big_endian: bool },
}

/// Why a value could not be read.
enum ValueError {
    /// The data ended.
    Eof,
    /// Malformed content.
    Bad(String),
}

/// The body reader: values in file order, by encoding.
struct Body<'a> {
    data: &'a [u8],
    pos: usize,
    encoding: Encoding,
    /// ASCII: 1-based line number of the current item.
    line: usize,
    /// ASCII: the current item's remaining tokens.
    tokens: std::vec::IntoIter<&'a str>,
}

impl<'a> Body<'a> {
    /// ASCII: moves to the next non-empty line (one element item per line).
    fn start_item(&mut self) -> Result<(), ValueError> {
        if self.encoding != Encoding::Ascii {
            return Ok(());
        }
        loop {
            if self.pos >= self.data.len() {
                return Err(ValueError::Eof);
            }
            let end = self.data[self.pos..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(self.data.len(), |e| self.pos + e);
            let text = std::str::from_utf8(&self.data[self.pos..end])
                .map_err(|_| ValueError::Bad("not valid ASCII/UTF-8 text".into()))?;
            self.pos = end + 1;
            self.line += 1;
            let tokens: Vec<&'a str> = text.split_ascii_whitespace().collect();
            if !tokens.is_empty() {
                self.tokens = tokens.into_iter();
                return Ok(());
            }
        }
    }

    /// ASCII: errors when the current item's line has values left over.
    fn end_item(&mut self) -> Result<(), ValueError> {
        match self.tokens.next() {
            Some(extra) => Err(ValueError::Bad(format!("unexpected extra value {extra:?}"))),
            None => Ok(()),
        }
    }

    fn value(&mut self, ty: Scalar) -> Result<f64, ValueError> {
        match self.encoding {
            Encoding::Ascii => {
                let tok = self.tokens.next().ok_or_else(|| {
                    ValueError::Bad("fewer values on the line than the header declares".into())
                })?;
                let v: f64 = tok
                    .parse()
                    .map_err(|_| ValueError::Bad(format!("{tok:?} is not a number")))?;
                if ty.is_integer() && v.fract() != 0.0 {
                    return Err(ValueError::Bad(format!("{tok:?} is not an integer")));
                }
                Ok(v)
            }
            Encoding::Binary { big_endian } => {
                let n = ty.size();
                let b = self
                    .data
                    .get(self.pos..self.pos + n)
                    .ok_or(ValueError::Eof)?;
                self.pos += n;
                Ok(ty.decode(b, big_endian))
            }
        }
    }
}

/// Reads a PLY mesh (ASCII or binary, either endianness).
///
/// # Errors
/// Unreadable file; a malformed header (named by line); a bad value, a non-finite coordinate, a
/// face with fewer than three corners or an out-of-range vertex index (named by line for ASCII,
/// by element and index for binary); a truncated body. Nothing panics on malformed input.
pub fn read_ply(path: &Path) -> Result<TriMesh, MeshIoError> {
    let data = std::fs::read(path).map_err(|source| MeshIoError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse_ply(&data, path)
}

/// [`read_ply`] of a file's bytes already in memory; `path` is the file they came from, named in
/// errors.
///
/// # Errors
/// As [`read_ply`], except that nothing is read from disk.
pub fn parse_ply(data: &[u8], path: &Path) -> Result<TriMesh, MeshIoError> {
    let syntax = |line: usize, reason: String| MeshIoError::Syntax {
        path: path.to_owned(),
        line,
        reason,
    };

    // Header.
    let mut pos = 0usize;
    let mut line_no = 0usize;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if pos >= data.len() {
            return Err(syntax(
                line_no.max(1),
                "the header has no end_header line".into(),
            ));
        }
        let end = data[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(data.len(), |e| pos + e);
        line_no += 1;
        let line = std::str::from_utf8(&data[pos..end])
            .map_err(|_| syntax(line_no, "the header is not ASCII text".into()))?
            .trim_end_matches('\r');
        pos = end + 1;
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        if line_no == 1 {
            if line.trim() != "ply" {
                return Err(syntax(
                    1,
                    format!("not a PLY file: the first line is {line:?}, expected \"ply\""),
                ));
            }
            continue;
        }
        match words.as_slice() {
            [] => {}
            ["comment", ..] | ["obj_info", ..] => {}
            ["format", fmt, version] => {
                if *version != "1.0" {
                    return Err(syntax(
                        line_no,
                        format!("unsupported PLY version {version:?}"),
                    ));
                }
                encoding = Some(match *fmt {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Binary { big_endian: false },
                    "binary_big_endian" => Encoding::Binary { big_endian: true },
                    other => return Err(syntax(line_no, format!("unknown PLY format {other:?}"))),
                });
            }
            ["element", name, count] => {
                let count: usize = count.parse().map_err(|_| {
                    syntax(
                        line_no,
                        format!("element count {count:?} is not a non-negative integer"),
                    )
                })?;
                // Another vertex element would add vertices without the first one's
                // attributes, and face indices would be checked against its count alone.
                if *name == "vertex" && elements.iter().any(|e| e.name == "vertex") {
                    return Err(syntax(
                        line_no,
                        "a second vertex element (a PLY file has one)".into(),
                    ));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            ["property", "list", count, item, name] => {
                let (Some(count_ty), Some(item_ty)) = (Scalar::parse(count), Scalar::parse(item))
                else {
                    return Err(syntax(
                        line_no,
                        format!("unknown list types {count:?} {item:?}"),
                    ));
                };
                if !count_ty.is_integer() {
                    return Err(syntax(
                        line_no,
                        format!("list count type {count:?} is not an integer type"),
                    ));
                }
                let el = elements
                    .last_mut()
                    .ok_or_else(|| syntax(line_no, "property before any element".into()))?;
                el.properties.push(Property::List {
                    name: name.to_string(),
                    count: count_ty,
                    item: item_ty,
                });
            }
            ["property", ty, name] => {
                let ty_parsed = Scalar::parse(ty)
                    .ok_or_else(|| syntax(line_no, format!("unknown property type {ty:?}")))?;
                let el = elements
                    .last_mut()
                    .ok_or_else(|| syntax(line_no, "property before any element".into()))?;
                el.properties.push(Property::Scalar {
                    name: name.to_string(),
                    ty: ty_parsed,
                });
            }
            ["end_header"] => break,
            _ => return Err(syntax(line_no, format!("malformed header line {line:?}"))),
        }
    }
    let encoding =
        encoding.ok_or_else(|| syntax(line_no, "the header has no format line".into()))?;

    let mut body = Body {
        data,
        pos,
        encoding,
        line: line_no,
        tokens: Vec::new().into_iter(),
    };
    let mut mesh = TriMesh::default();
    let mut vertex_count = None;
    let mut polygons: Vec<(usize, usize, Vec<i64>)> = Vec::new(); // (face index, line, corners)
    let mut values: Vec<f64> = Vec::new();
    for el in &elements {
        let is_vertex = el.name == "vertex";
        let is_face = el.name == "face";
        let find = |names: &[&str]| -> Option<usize> {
            el.properties
                .iter()
                .position(|p| names.contains(&p.name()) && matches!(p, Property::Scalar { .. }))
        };
        let pos_idx = [find(&["x"]), find(&["y"]), find(&["z"])];
        let nrm_idx = [find(&["nx"]), find(&["ny"]), find(&["nz"])];
        let uv_idx = [
            find(&["s", "u", "texture_u", "texture_s"]),
            find(&["t", "v", "texture_v", "texture_t"]),
        ];
        let col_idx = [
            find(&["red", "diffuse_red", "r"]),
            find(&["green", "diffuse_green", "g"]),
            find(&["blue", "diffuse_blue", "b"]),
        ];
        let face_idx = el.properties.iter().position(|p| {
            matches!(p, Property::List { name, .. } if name == "vertex_indices" || name == "vertex_index")
        });
        if is_vertex {
            if pos_idx.iter().any(Option::is_none) {
                return Err(syntax(line_no, "the vertex element lacks x, y or z".into()));
            }
            vertex_count = Some(el.count);
            // Reserve no more than the data could possibly hold.
            let cap = el.count.min(data.len() / 3 + 1);
            mesh.vertices.reserve(cap);
        }
        if is_face && face_idx.is_none() {
            return Err(syntax(
                line_no,
                "the face element has no vertex_indices list".into(),
            ));
        }
        let has_n = is_vertex && nrm_idx.iter().all(Option::is_some);
        let has_uv = is_vertex && uv_idx.iter().all(Option::is_some);
        let has_c = is_vertex && col_idx.iter().all(Option::is_some);
        if el.properties.is_empty() && encoding != Encoding::Ascii {
            // A binary item without properties takes no bytes: nothing to read, whatever the
            // count (looping over a count of 10^17 would never end).
            continue;
        }
        for index in 0..el.count {
            let fail = |body: &Body, e: ValueError| match (e, encoding) {
                (ValueError::Eof, _) => MeshIoError::Truncated {
                    path: path.to_owned(),
                    element: el.name.clone(),
                    index,
                    count: el.count,
                },
                (ValueError::Bad(reason), Encoding::Ascii) => MeshIoError::Syntax {
                    path: path.to_owned(),
                    line: body.line,
                    reason: format!("{} {index}: {reason}", el.name),
                },
                (ValueError::Bad(reason), Encoding::Binary { .. }) => MeshIoError::Element {
                    path: path.to_owned(),
                    element: el.name.clone(),
                    index,
                    reason,
                },
            };
            body.start_item().map_err(|e| fail(&body, e))?;
            values.clear();
            let mut face: Option<Vec<i64>> = None;
            for (k, prop) in el.properties.iter().enumerate() {
                match *prop {
                    Property::Scalar { ty, .. } => {
                        let v = body.value(ty).map_err(|e| fail(&body, e))?;
                        values.push(v);
                    }
                    Property::List { count, item, .. } => {
                        let n = body.value(count).map_err(|e| fail(&body, e))?;
                        if !(0.0..=MAX_POLYGON_CORNERS as f64).contains(&n) {
                            return Err(fail(
                                &body,
                                ValueError::Bad(format!("list length {n} is out of range")),
                            ));
                        }
                        let mut list = Vec::with_capacity(n as usize);
                        for _ in 0..n as usize {
                            let v = body.value(item).map_err(|e| fail(&body, e))?;
                            list.push(v);
                        }
                        values.push(f64::NAN);
                        if is_face && Some(k) == face_idx {
                            if let Some(bad) =
                                list.iter().find(|v| v.fract() != 0.0 || !v.is_finite())
                            {
                                return Err(fail(
                                    &body,
                                    ValueError::Bad(format!(
                                        "vertex index {bad} is not an integer"
                                    )),
                                ));
                            }
                            face = Some(list.iter().map(|&v| v as i64).collect());
                        }
                    }
                }
            }
            body.end_item().map_err(|e| fail(&body, e))?;
            if is_vertex {
                let get = |idx: [Option<usize>; 3]| idx.map(|i| i.map_or(0.0, |i| values[i]));
                let p = get(pos_idx);
                if !p.iter().all(|c| c.is_finite()) {
                    return Err(fail(
                        &body,
                        ValueError::Bad(format!("position {p:?} is not finite")),
                    ));
                }
                mesh.vertices.push(p);
                if has_n {
                    let n = get(nrm_idx);
                    if !n.iter().all(|c| c.is_finite()) {
                        return Err(fail(
                            &body,
                            ValueError::Bad(format!("normal {n:?} is not finite")),
                        ));
                    }
                    mesh.normals.push(n);
                }
                if has_uv {
                    mesh.uvs.push(uv_idx.map(|i| i.map_or(0.0, |i| values[i])));
                }
                if has_c {
                    let integer = col_idx.iter().flatten().all(|&i| match &el.properties[i] {
                        Property::Scalar { ty, .. } => ty.is_integer(),
                        Property::List { .. } => false,
                    });
                    let c = get(col_idx).map(|v| if integer { v / 255.0 } else { v });
                    mesh.colors
                        .push(c.map(|v| srgb_to_linear(v.clamp(0.0, 1.0) as f32)));
                }
            }
            if let Some(corners) = face {
                if corners.len() < 3 {
                    return Err(fail(
                        &body,
                        ValueError::Bad(format!(
                            "a face needs 3 or more corners, found {}",
                            corners.len()
                        )),
                    ));
                }
                polygons.push((index, body.line, corners));
            }
        }
    }
    let nv =
        vertex_count.ok_or_else(|| syntax(line_no, "the file has no vertex element".into()))?;
    for (index, line, corners) in polygons {
        if let Some(&bad) = corners.iter().find(|&&i| i < 0 || i as usize >= nv) {
            let reason = format!("vertex index {bad} is out of range (the file has {nv} vertices)");
            return Err(match encoding {
                Encoding::Ascii => MeshIoError::Syntax {
                    path: path.to_owned(),
                    line,
                    reason: format!("face {index}: {reason}"),
                },
                Encoding::Binary { .. } => MeshIoError::Element {
                    path: path.to_owned(),
                    element: "face".into(),
                    index,
                    reason,
                },
            });
        }
        for i in 1..corners.len() - 1 {
            mesh.triangles
                .push([corners[0] as u32, corners[i] as u32, corners[i + 1] as u32]);
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::linear_to_srgb as srgb;

    fn sample_mesh() -> TriMesh {
        let mut m = TriMesh::new(
            vec![
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 1.5],
                [0.0, 1.0, 2.0],
                [1.0, 1.0, 0.5],
            ],
            vec![[0, 1, 2], [1, 3, 2]],
        );
        m.normals = vec![[0.0, 0.0, -1.0]; 4];
        m.uvs = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        m.colors = vec![
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.5, 0.5, 0.5],
        ];
        m
    }

    #[test]
    fn binary_and_ascii_round_trip_with_all_attributes() {
        let dir = tempfile::tempdir().unwrap();
        let m = sample_mesh();
        for format in [PlyFormat::BinaryLittleEndian, PlyFormat::Ascii] {
            let path = dir.path().join("m.ply");
            write_ply_with(&path, &m, format).unwrap();
            let back = read_ply(&path).unwrap();
            assert_eq!(back.vertices, m.vertices);
            assert_eq!(back.triangles, m.triangles);
            assert_eq!(back.normals, m.normals);
            assert_eq!(back.uvs, m.uvs);
            for (a, b) in back.colors.iter().zip(&m.colors) {
                for k in 0..3 {
                    // 8-bit sRGB quantisation.
                    assert!(
                        (srgb(a[k]) - srgb(b[k])).abs() <= 0.5 / 255.0 + 1e-6,
                        "{a:?} vs {b:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn big_endian_quads_and_extra_properties_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("be.ply");
        let mut bytes = b"ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\nproperty uchar flags\nelement face 1\nproperty list uchar uint vertex_indices\nproperty float quality\nend_header\n".to_vec();
        for (i, p) in [
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ]
        .iter()
        .enumerate()
        {
            for c in p {
                bytes.extend_from_slice(&f64::to_be_bytes(*c));
            }
            bytes.push(i as u8);
        }
        bytes.push(4);
        for i in [0u32, 1, 2, 3] {
            bytes.extend_from_slice(&i.to_be_bytes());
        }
        bytes.extend_from_slice(&0.5f32.to_be_bytes());
        std::fs::write(&path, &bytes).unwrap();
        let m = read_ply(&path).unwrap();
        assert_eq!(m.vertices[2], [1.0, 1.0, 1.0]);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        // Truncating anywhere in the body is an error that names the element.
        let cut = bytes.len() - 7;
        std::fs::write(&path, &bytes[..cut]).unwrap();
        let err = read_ply(&path).unwrap_err().to_string();
        assert!(
            err.contains("be.ply") && err.contains("truncated") && err.contains("face 0"),
            "{err}"
        );
        std::fs::write(&path, &bytes[..bytes.len() - 60]).unwrap();
        let err = read_ply(&path).unwrap_err().to_string();
        assert!(err.contains("vertex 2 of 4"), "{err}");
    }

    #[test]
    fn a_binary_element_without_properties_is_skipped_whatever_its_count() {
        // Its items take no bytes; this count used to spin the reader for ever.
        let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement padding 99999999999999999\nend_header\n".to_vec();
        for c in [1.0f32, 2.0, 3.0] {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
        let m = parse_ply(&bytes, Path::new("empty_items.ply")).unwrap();
        assert_eq!(m.vertices, [[1.0, 2.0, 3.0]]);
        // In ASCII every item is a line, so the same header is a truncated file.
        let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement padding 99999999999999999\nend_header\n1 2 3\n";
        let err = parse_ply(text.as_bytes(), Path::new("empty_items.ply"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("truncated") && err.contains("padding 0"),
            "{err}"
        );
    }

    #[test]
    fn a_second_vertex_element_is_an_error() {
        // The second element's vertices came without the first one's normals, so the mesh had
        // fewer normals than vertices.
        let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 1 0 0 -1\n1 0 1\n";
        let err = parse_ply(text.as_bytes(), Path::new("two.ply"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("two.ply:10:") && err.contains("second vertex element"),
            "{err}"
        );
    }

    #[test]
    fn bad_content_is_named_by_line_or_element() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.ply");
        let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
        let cases = [
            (
                format!("{head}0 0 1\n1 0 1\n0 1 1\n3 0 1 7\n"),
                ":13:",
                "out of range",
            ),
            (
                format!("{head}0 0 1\nnan 0 1\n0 1 1\n3 0 1 2\n"),
                ":11:",
                "not finite",
            ),
            (
                format!("{head}0 0 1\n1 0\n0 1 1\n3 0 1 2\n"),
                ":11:",
                "fewer values",
            ),
            (
                format!("{head}0 0 1\n1 0 1\n0 1 1\n2 0 1\n"),
                ":13:",
                "3 or more",
            ),
            (
                format!("{head}0 0 1\n1 0 1\n"),
                "vertex 2 of 3",
                "truncated",
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex x\n".to_string(),
                ":3:",
                "element count",
            ),
            ("plx\n".to_string(), ":1:", "not a PLY"),
        ];
        for (text, place, what) in cases {
            std::fs::write(&path, text).unwrap();
            let err = read_ply(&path).unwrap_err().to_string();
            assert!(
                err.contains("bad.ply") && err.contains(place) && err.contains(what),
                "{err}"
            );
        }
        // Binary: a bad index names the face element.
        let m = TriMesh::new(vec![[0.0; 3]; 3], vec![[0, 1, 5]]);
        write_ply(&path, &m).unwrap();
        let err = read_ply(&path).unwrap_err().to_string();
        assert!(
            err.contains("face 0") && err.contains("out of range"),
            "{err}"
        );
    }
}
