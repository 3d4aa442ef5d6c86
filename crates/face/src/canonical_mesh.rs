//! MediaPipe's canonical metric face mesh, read from `geometry_pipeline_metadata_landmarks.binarypb`
//! (the `GeometryPipelineMetadata` protobuf of MediaPipe's face-geometry module).
//!
//! Proto fields used: `canonical_mesh = 1` (`Mesh3d`: `vertex_buffer = 3`, five floats per
//! vertex `x, y, z, u, v`; `index_buffer = 4`, three indices per triangle), and
//! `procrustes_landmark_basis = 2` (`WeightedLandmarkRef`: `landmark_id = 1`, `weight = 2`).
//! Repeated fields may be packed or not; both are read. The file is 19 kB; a hand-written
//! wire-format reader avoids a protobuf dependency.

use std::path::Path;

use crate::{FaceError, ModelFile, NUM_LANDMARKS};

/// Number of triangles of the FaceMesh surface.
pub const NUM_TRIANGLES: usize = 898;

/// The canonical face in visage's camera axes: x right, y down, z forward (away from the
/// viewer), **metres**; the face looks towards −z. (MediaPipe stores centimetres with y up and
/// z towards the viewer; the conversion is `(x, −y, −z) / 100`, a proper rotation.)
#[derive(Clone, Debug, PartialEq)]
pub struct CanonicalMesh {
    /// 468 vertices, one per FaceMesh landmark (same index).
    pub vertices: Vec<[f64; 3]>,
    /// Texture coordinates in [0, 1]², MediaPipe's UV layout with v up (OBJ's and the
    /// renderer's convention; the metadata stores v down).
    pub uvs: Vec<[f64; 2]>,
    /// 898 triangles.
    pub triangles: Vec<[u32; 3]>,
    /// `(landmark index, weight)` of MediaPipe's Procrustes basis (the stable, rigid points).
    pub procrustes_basis: Vec<(usize, f64)>,
}

struct Wire<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Wire<'a> {
    fn varint(&mut self) -> Option<u64> {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let b = *self.buf.get(self.pos)?;
            self.pos += 1;
            v |= ((b & 0x7f) as u64) << shift;
            if b < 0x80 {
                return Some(v);
            }
        }
        None
    }

    fn bytes(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.buf.get(self.pos..self.pos.checked_add(n)?)?;
        self.pos += n;
        Some(s)
    }

    /// Next field: number and value.
    fn field(&mut self) -> Option<Result<(u64, Value<'a>), ()>> {
        if self.pos >= self.buf.len() {
            return None;
        }
        let Some(key) = self.varint() else {
            return Some(Err(()));
        };
        let value = match key & 7 {
            0 => self.varint().map(Value::Varint),
            1 => self.bytes(8).map(|_| Value::Other),
            2 => self
                .varint()
                .and_then(|n| self.bytes(usize::try_from(n).ok()?))
                .map(Value::Bytes),
            5 => self
                .bytes(4)
                .map(|b| Value::Fixed32([b[0], b[1], b[2], b[3]])),
            _ => None,
        };
        Some(value.map(|v| (key >> 3, v)).ok_or(()))
    }
}

enum Value<'a> {
    Varint(u64),
    Fixed32([u8; 4]),
    Bytes(&'a [u8]),
    Other,
}

impl CanonicalMesh {
    /// Loads and verifies `geometry_pipeline_metadata_landmarks.binarypb` from the model directory.
    pub fn load(models: &Path) -> Result<Self, FaceError> {
        Self::parse(&ModelFile::GeometryPipelineMetadata.read(models)?)
    }

    /// Parses the protobuf bytes.
    pub fn parse(bytes: &[u8]) -> Result<Self, FaceError> {
        let bad = |reason: String| FaceError::Geometry {
            name: ModelFile::GeometryPipelineMetadata.file_name().into(),
            reason,
        };
        let mut floats = Vec::new();
        let mut indices = Vec::new();
        let mut basis = Vec::new();
        let mut top = Wire { buf: bytes, pos: 0 };
        while let Some(f) = top.field() {
            match f.map_err(|()| bad("malformed protobuf".into()))? {
                (1, Value::Bytes(mesh)) => {
                    let mut m = Wire { buf: mesh, pos: 0 };
                    while let Some(g) = m.field() {
                        match g.map_err(|()| bad("malformed Mesh3d".into()))? {
                            (3, Value::Fixed32(b)) => floats.push(f32::from_le_bytes(b)),
                            (3, Value::Bytes(p)) => floats.extend(
                                p.chunks_exact(4)
                                    .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                            ),
                            (4, Value::Varint(i)) => indices.push(i),
                            (4, Value::Bytes(p)) => {
                                let mut w = Wire { buf: p, pos: 0 };
                                while w.pos < p.len() {
                                    indices.push(w.varint().ok_or_else(|| {
                                        bad("malformed packed index buffer".into())
                                    })?);
                                }
                            }
                            _ => {}
                        }
                    }
                }
                (2, Value::Bytes(r)) => {
                    let (mut id, mut weight) = (None, 0.0f32);
                    let mut w = Wire { buf: r, pos: 0 };
                    while let Some(g) = w.field() {
                        match g.map_err(|()| bad("malformed WeightedLandmarkRef".into()))? {
                            (1, Value::Varint(i)) => id = Some(i),
                            (2, Value::Fixed32(b)) => weight = f32::from_le_bytes(b),
                            _ => {}
                        }
                    }
                    let id = id.ok_or_else(|| bad("basis entry without landmark_id".into()))?;
                    if id as usize >= NUM_LANDMARKS || !(weight.is_finite() && weight >= 0.0) {
                        return Err(bad(format!("basis entry ({id}, {weight}) out of range")));
                    }
                    basis.push((id as usize, weight as f64));
                }
                _ => {}
            }
        }
        if floats.len() != 5 * NUM_LANDMARKS || floats.iter().any(|v| !v.is_finite()) {
            return Err(bad(format!(
                "{} vertex floats, expected {} finite",
                floats.len(),
                5 * NUM_LANDMARKS
            )));
        }
        if indices.len() != 3 * NUM_TRIANGLES
            || indices.iter().any(|&i| i as usize >= NUM_LANDMARKS)
        {
            return Err(bad(format!(
                "{} indices, expected {} below {NUM_LANDMARKS}",
                indices.len(),
                3 * NUM_TRIANGLES
            )));
        }
        if basis.is_empty() {
            return Err(bad("no Procrustes landmark basis".into()));
        }
        let vertices = floats
            .chunks_exact(5)
            .map(|v| [v[0] as f64 * 0.01, -v[1] as f64 * 0.01, -v[2] as f64 * 0.01])
            .collect();
        // The metadata's v runs down the texture image; visage's (OBJ's) runs up.
        let uvs = floats
            .chunks_exact(5)
            .map(|v| [v[3] as f64, 1.0 - v[4] as f64])
            .collect();
        let triangles = indices
            .chunks_exact(3)
            .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
            .collect();
        Ok(CanonicalMesh {
            vertices,
            uvs,
            triangles,
            procrustes_basis: basis,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_garbage() {
        assert!(CanonicalMesh::parse(b"").is_err());
        assert!(CanonicalMesh::parse(&[0x0a, 0xff, 0xff, 0xff, 0xff, 0x0f]).is_err());
        assert!(CanonicalMesh::parse(&[0x0a, 0x02, 0x1d, 0x00]).is_err());
    }
}
