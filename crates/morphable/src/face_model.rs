//! The compact face model the fit uses: the face region of a morphable model (ICT-FaceKit
//! vertices 0–9408) — neutral shape, identity and expression modes, triangles, UVs — and where
//! MediaPipe's 468 landmarks lie on it. Built from an ICT-FaceKit folder ([`FaceModel::from_ict`])
//! and stored in a small binary file; the one derived from the 30-identity subset ships inside
//! the crate ([`FaceModel::embedded`]), so a user's clone fits faces without the model folder.
//!
//! # File format (little endian)
//! `VISAGEFM`, version `u32`, then counts `u32`: vertices n, triangles, identity modes,
//! expression modes, landmarks; expression names (`u16` length + UTF-8 each); neutral `n × 3`
//! `f32` (metres); UVs `n × 2` `f32`; triangles `× 3` `u32`; landmarks `× (3 u32 + 3 f32 +
//! 3 f32)` (triangle, barycentrics, offset in metres); identity then expression deltas, `modes × n × 3` IEEE `f16` in
//! millimetres (resolution ≤ 0.02 mm for deltas under 40 mm).

use std::path::Path;

use half::f16;
use visage_mesh::io::{read_obj_with, ObjReadOptions};

use crate::binary_reader::Reader;
use crate::{CanonicalCorrespondence, IctModel, MorphableError, Region, SurfacePoint};

const MAGIC: &[u8; 8] = b"VISAGEFM";
const VERSION: u32 = 2;
/// Deltas are stored in millimetres (f16 keeps ~3 significant digits).
const DELTA_UNITS_PER_METRE: f32 = 1000.0;

/// The compact model derived from ICT-FaceKit's 30-identity subset (MIT licence; see
/// `crates/morphable/data/README.md` for the notice and the command that regenerates it).
const EMBEDDED: &[u8] = include_bytes!("../data/ict_face_model.bin");

/// A linear face model on a fixed triangle mesh: `S(p, e) = S̄ + Σ p_i U_i + Σ e_j B_j`, in the
/// model frame (ICT axes: x to the image right, y up, the face looking along +z; metres).
#[derive(Clone, Debug, PartialEq)]
pub struct FaceModel {
    /// S̄, #V.
    pub neutral: Vec<[f32; 3]>,
    /// Texture coordinates per vertex, [0, 1]², OBJ convention (v up).
    pub uvs: Vec<[f32; 2]>,
    pub triangles: Vec<[u32; 3]>,
    /// Identity modes U_i (#V each), weights ~ N(0, 1).
    pub identity: Vec<Vec<[f32; 3]>>,
    /// Expression names (ICT-FaceKit's, ARKit-style: `jawOpen`, `eyeBlink_L`, …).
    pub expression_names: Vec<String>,
    /// Expression modes B_j (#V each), weights in [0, 1].
    pub expressions: Vec<Vec<[f32; 3]>>,
    /// Where FaceMesh landmark k lies on the model (468, landmark order).
    pub landmarks: Vec<SurfacePoint>,
    /// Landmark k's offset from its surface point (model frame, metres): FaceMesh's landmark
    /// is `Σ β X + offset`.
    pub landmark_offsets: Vec<[f32; 3]>,
}

impl FaceModel {
    /// The model shipped with the crate (ICT-FaceKit's face region, 30 identity modes, the 53
    /// listed expressions).
    pub fn embedded() -> FaceModel {
        match FaceModel::parse(EMBEDDED) {
            Ok(m) => m,
            Err(e) => unreachable!("the embedded face model is checked by a test: {e}"),
        }
    }

    /// The face region of `ict` with the landmark correspondence `landmarks` (computed on the
    /// same model) and the neutral mesh's UVs. The neutral shape is the ICT face closest to
    /// MediaPipe's canonical face (`landmarks.identity` baked in), so the identity prior is
    /// centred on the mean face the landmark network was built around.
    ///
    /// # Errors
    /// When the neutral mesh's UVs cannot be read.
    pub fn from_ict(
        ict: &IctModel,
        landmarks: &CanonicalCorrespondence,
    ) -> Result<FaceModel, MorphableError> {
        let uvs = vertex_uvs(ict)?;
        let face = Region::Face.range();
        let f32s = |v: &[[f64; 3]]| -> Vec<[f32; 3]> {
            v[face.clone()]
                .iter()
                .map(|p| p.map(|c| c as f32))
                .collect()
        };
        let mut neutral = ict.neutral.clone();
        for (mode, &w) in ict.identity_modes.iter().zip(&landmarks.identity) {
            for (p, d) in neutral.iter_mut().zip(mode) {
                for c in 0..3 {
                    p[c] += w * d[c];
                }
            }
        }
        Ok(FaceModel {
            neutral: f32s(&neutral),
            uvs: uvs[face.clone()]
                .iter()
                .map(|t| t.map(|c| c as f32))
                .collect(),
            triangles: ict.triangles_below(face.end),
            identity: ict.identity_modes.iter().map(|m| f32s(m)).collect(),
            expression_names: ict.expression_names.clone(),
            expressions: ict.expression_modes.iter().map(|m| f32s(m)).collect(),
            landmarks: landmarks.points.clone(),
            landmark_offsets: landmarks
                .offsets_m
                .iter()
                .map(|o| o.map(|c| c as f32))
                .collect(),
        })
    }

    pub fn vertex_count(&self) -> usize {
        self.neutral.len()
    }

    /// Index of the expression called `name`.
    pub fn expression_index(&self, name: &str) -> Option<usize> {
        self.expression_names.iter().position(|e| e == name)
    }

    /// `S(p, e)` into `out` (#V, metres, model frame). Missing trailing weights count as 0.
    pub fn shape(&self, identity: &[f64], expression: &[f64], out: &mut Vec<[f64; 3]>) {
        out.clear();
        out.extend(self.neutral.iter().map(|p| p.map(f64::from)));
        let modes = self
            .identity
            .iter()
            .zip(identity)
            .chain(self.expressions.iter().zip(expression));
        for (mode, &w) in modes.filter(|(_, &w)| w != 0.0) {
            for (p, d) in out.iter_mut().zip(mode) {
                for c in 0..3 {
                    p[c] += w * d[c] as f64;
                }
            }
        }
    }

    /// The model in its file format.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::new();
        b.extend_from_slice(MAGIC);
        let u32s = |b: &mut Vec<u8>, v: u32| b.extend_from_slice(&v.to_le_bytes());
        let f32s = |b: &mut Vec<u8>, v: f32| b.extend_from_slice(&v.to_le_bytes());
        u32s(&mut b, VERSION);
        for count in [
            self.vertex_count(),
            self.triangles.len(),
            self.identity.len(),
            self.expressions.len(),
            self.landmarks.len(),
        ] {
            u32s(&mut b, count as u32);
        }
        for name in &self.expression_names {
            b.extend_from_slice(&(name.len() as u16).to_le_bytes());
            b.extend_from_slice(name.as_bytes());
        }
        self.neutral.iter().flatten().for_each(|&v| f32s(&mut b, v));
        self.uvs.iter().flatten().for_each(|&v| f32s(&mut b, v));
        self.triangles
            .iter()
            .flatten()
            .for_each(|&v| u32s(&mut b, v));
        for (l, o) in self.landmarks.iter().zip(&self.landmark_offsets) {
            l.triangle.iter().for_each(|&v| u32s(&mut b, v));
            l.bary.iter().for_each(|&v| f32s(&mut b, v as f32));
            o.iter().for_each(|&v| f32s(&mut b, v));
        }
        for mode in self.identity.iter().chain(&self.expressions) {
            for &v in mode.iter().flatten() {
                b.extend_from_slice(&f16::from_f32(v * DELTA_UNITS_PER_METRE).to_le_bytes());
            }
        }
        b
    }

    /// The 468 landmarks on a shape with the model's topology (`shape` indexed as its
    /// vertices): each surface point plus its calibrated offset.
    pub fn landmark_points(&self, shape: &[[f64; 3]]) -> Vec<[f64; 3]> {
        self.landmarks
            .iter()
            .zip(&self.landmark_offsets)
            .map(|(l, o)| {
                let p = l.on(shape);
                std::array::from_fn(|c| p[c] + o[c] as f64)
            })
            .collect()
    }

    /// Writes the model file.
    ///
    /// # Errors
    /// When `path` cannot be written.
    pub fn write(&self, path: &Path) -> Result<(), MorphableError> {
        std::fs::write(path, self.to_bytes()).map_err(|source| MorphableError::Io {
            path: path.to_owned(),
            source,
        })
    }

    /// Reads a model file.
    ///
    /// # Errors
    /// An unreadable file, or one that is not a valid model file (named).
    pub fn read(path: &Path) -> Result<FaceModel, MorphableError> {
        let bytes = std::fs::read(path).map_err(|source| MorphableError::Io {
            path: path.to_owned(),
            source,
        })?;
        FaceModel::parse(&bytes).map_err(|reason| MorphableError::Indices {
            path: path.to_owned(),
            reason: format!("not a visage face model: {reason}"),
        })
    }

    /// Parses the file format; the error says what is wrong.
    pub fn parse(bytes: &[u8]) -> Result<FaceModel, String> {
        let mut r = Reader::new(bytes);
        r.header(MAGIC, VERSION)?;
        let mut count = || r.u32().map(|v| v as usize);
        let (n, n_tri, n_id, n_ex, n_lm) = (count()?, count()?, count()?, count()?, count()?);
        let mut expression_names = Vec::with_capacity(n_ex);
        for _ in 0..n_ex {
            let len = u16::from_le_bytes([r.u8()?, r.u8()?]) as usize;
            let name = std::str::from_utf8(r.take(len)?).map_err(|e| e.to_string())?;
            expression_names.push(name.to_owned());
        }
        let neutral = (0..n).map(|_| r.f32x3()).collect::<Result<_, _>>()?;
        let uvs = (0..n)
            .map(|_| Ok([r.f32()?, r.f32()?]))
            .collect::<Result<_, String>>()?;
        let triangles: Vec<[u32; 3]> = (0..n_tri)
            .map(|_| Ok([r.u32()?, r.u32()?, r.u32()?]))
            .collect::<Result<_, String>>()?;
        if triangles.iter().flatten().any(|&i| i as usize >= n) {
            return Err("a triangle indexes past the vertices".into());
        }
        let mut landmark_offsets = Vec::with_capacity(n_lm);
        let landmarks: Vec<SurfacePoint> = (0..n_lm)
            .map(|_| {
                let triangle = [r.u32()?, r.u32()?, r.u32()?];
                let bary = r.f32x3()?.map(f64::from);
                landmark_offsets.push(r.f32x3()?);
                Ok(SurfacePoint { triangle, bary })
            })
            .collect::<Result<_, String>>()?;
        if landmarks
            .iter()
            .flat_map(|l| l.triangle)
            .any(|i| i as usize >= n)
        {
            return Err("a landmark lies past the vertices".into());
        }
        let mut mode = || -> Result<Vec<[f32; 3]>, String> {
            (0..n)
                .map(|_| {
                    let mut p = [0.0f32; 3];
                    for c in &mut p {
                        let h = f16::from_le_bytes([r.u8()?, r.u8()?]);
                        *c = h.to_f32() / DELTA_UNITS_PER_METRE;
                    }
                    Ok(p)
                })
                .collect()
        };
        let identity = (0..n_id).map(|_| mode()).collect::<Result<_, _>>()?;
        let expressions = (0..n_ex).map(|_| mode()).collect::<Result<_, _>>()?;
        r.finish()?;
        Ok(FaceModel {
            neutral,
            uvs,
            triangles,
            identity,
            expression_names,
            expressions,
            landmarks,
            landmark_offsets,
        })
    }
}

/// One texture coordinate per ICT vertex: the neutral mesh read with its UVs (vertices copied
/// at seams) matched corner by corner with the model's triangles (file numbering); a vertex on
/// a seam keeps the first UV met.
fn vertex_uvs(ict: &IctModel) -> Result<Vec<[f64; 2]>, MorphableError> {
    let path = ict.dir.join(crate::ict_model::NEUTRAL_FILE);
    let with_uvs = read_obj_with(&path, &ObjReadOptions::default())?.mesh;
    let mut uvs = vec![[f64::NAN; 2]; ict.vertex_count()];
    if with_uvs.uvs.is_empty() || with_uvs.triangles.len() != ict.triangles.len() {
        return Err(MorphableError::Indices {
            path,
            reason: "the neutral mesh has no texture coordinates for its faces".into(),
        });
    }
    for (t, u) in ict.triangles.iter().zip(&with_uvs.triangles) {
        for (&i, &j) in t.iter().zip(u) {
            let uv = &mut uvs[i as usize];
            if uv[0].is_nan() {
                *uv = with_uvs.uvs[j as usize];
            }
        }
    }
    for uv in &mut uvs {
        if uv[0].is_nan() {
            *uv = [0.0, 0.0]; // a vertex no face uses
        }
    }
    Ok(uvs)
}
