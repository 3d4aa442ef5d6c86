//! The ICT-FaceKit morphable model: import of the `FaceXModel/` folder layout.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use visage_mesh::io::{read_obj_with, ObjReadOptions};

use crate::{MorphableError, CM_TO_M};

/// Number of landmark vertices (the 68 Multi-PIE / iBUG points).
pub const LANDMARK_COUNT: usize = 68;

/// The folder inside a checkout of the ICT-FaceKit repository that holds the model.
const MODEL_FOLDER: &str = "FaceXModel";
/// The neutral mesh S̄.
pub(crate) const NEUTRAL_FILE: &str = "generic_neutral_mesh.obj";
/// Expression names, landmark and fitting vertex sets.
const INDICES_FILE: &str = "vertex_indices.json";

/// Which modes to import (all by default). Loading is the slow part (one 2.5 MB OBJ per mode),
/// so tests and quick runs ask for fewer.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImportOptions {
    /// Import at most this many identity modes (`identity000.obj`, `identity001.obj`, … in
    /// order); `None`: every consecutive file present.
    pub max_identities: Option<usize>,
    /// Import exactly these expressions, in this order (each must have its file); `None`: every
    /// expression listed in `vertex_indices.json` whose file is present, in the listed order.
    pub expressions: Option<Vec<String>>,
}

/// The subset of `vertex_indices.json` the importer reads.
#[derive(serde::Deserialize)]
struct VertexIndices {
    expressions: Vec<String>,
    idx_to_landmark_verts: Vec<i64>,
}

/// An imported ICT-FaceKit model, in metres, in the ICT frame (x image-right when seen from
/// the front, y up, the face looking along +z). All vertex arrays have
/// [`IctModel::vertex_count`] entries (#V = 26,719 for the ICT topology).
#[derive(Clone, Debug, PartialEq)]
pub struct IctModel {
    /// The `FaceXModel` folder the model was read from.
    pub dir: PathBuf,
    /// Neutral mesh S̄, #V positions, metres.
    pub neutral: Vec<[f64; 3]>,
    /// Triangles (polygons fanned, file orientation), indices into the vertex arrays.
    pub triangles: Vec<[u32; 3]>,
    /// For each triangle, the polygon of the OBJ file it came from (0-based).
    pub triangle_polygon: Vec<u32>,
    /// File stems of the identity modes (`identity000`, …).
    pub identity_names: Vec<String>,
    /// Identity modes `U_i = identity_i − S̄`, #V offsets each, metres; weights ~ N(0, 1).
    pub identity_modes: Vec<Vec<[f64; 3]>>,
    /// ARKit names of the expression modes (`jawOpen`, `eyeBlink_L`, …).
    pub expression_names: Vec<String>,
    /// Expression modes `B_j = expression_j − S̄`, #V offsets each, metres; weights in [0, 1].
    pub expression_modes: Vec<Vec<[f64; 3]>>,
    /// The 68 landmark vertex indices (`idx_to_landmark_verts`), iBUG order.
    pub landmarks: [u32; LANDMARK_COUNT],
}

fn indices_error(path: &Path, reason: String) -> MorphableError {
    MorphableError::Indices {
        path: path.to_owned(),
        reason,
    }
}

/// `dir` itself when it holds the neutral mesh, else `dir/FaceXModel` when that does (a
/// checkout of the repository).
fn model_folder(dir: &Path) -> Result<PathBuf, MorphableError> {
    if dir.join(NEUTRAL_FILE).is_file() {
        return Ok(dir.to_owned());
    }
    let nested = dir.join(MODEL_FOLDER);
    if nested.join(NEUTRAL_FILE).is_file() {
        return Ok(nested);
    }
    Err(MorphableError::MissingFile {
        path: dir.join(NEUTRAL_FILE),
        what: "the ICT-FaceKit neutral mesh; pass the FaceXModel folder or a checkout of the repository",
    })
}

impl IctModel {
    /// Imports every mode of the model in `dir` (see [`IctModel::load_with`]).
    pub fn load(dir: &Path) -> Result<IctModel, MorphableError> {
        Self::load_with(dir, &ImportOptions::default())
    }

    /// Imports the model in `dir`: either the `FaceXModel` folder or a checkout of the
    /// ICT-FaceKit repository containing it. Reads `generic_neutral_mesh.obj` (positions and
    /// polygons), `vertex_indices.json` (expression names, 68 landmarks), the identity files
    /// `identityNNN.obj` from 000 up to the first missing one, and the expression files
    /// `<name>.obj` that are present. Converts centimetres to metres; modes are mesh − neutral.
    ///
    /// # Errors
    /// A missing neutral mesh or index file, a malformed OBJ or JSON, a mode file whose vertex
    /// count differs from the neutral mesh, a landmark index out of range, a requested
    /// expression without a file — each naming the file.
    pub fn load_with(dir: &Path, options: &ImportOptions) -> Result<IctModel, MorphableError> {
        let dir = model_folder(dir)?;
        let neutral_path = dir.join(NEUTRAL_FILE);
        // Positions and fanned polygons with the file's vertex numbering (no UV-seam copies).
        let obj = read_obj_with(&neutral_path, &ObjReadOptions::POSITIONS_AND_FACES)?;
        let neutral: Vec<[f64; 3]> = obj
            .mesh
            .vertices
            .iter()
            .map(|p| p.map(|c| c * CM_TO_M))
            .collect();
        let n = neutral.len();
        let triangles = obj.mesh.triangles;
        let triangle_polygon = obj.triangle_face;

        let indices_path = dir.join(INDICES_FILE);
        if !indices_path.is_file() {
            return Err(MorphableError::MissingFile {
                path: indices_path,
                what: "ICT-FaceKit vertex indices",
            });
        }
        let text = std::fs::read_to_string(&indices_path).map_err(|source| MorphableError::Io {
            path: indices_path.clone(),
            source,
        })?;
        let indices: VertexIndices =
            serde_json::from_str(&text).map_err(|e| indices_error(&indices_path, e.to_string()))?;
        if indices.idx_to_landmark_verts.len() != LANDMARK_COUNT {
            return Err(indices_error(
                &indices_path,
                format!(
                    "idx_to_landmark_verts has {} entries, expected {LANDMARK_COUNT}",
                    indices.idx_to_landmark_verts.len()
                ),
            ));
        }
        let mut landmarks = [0u32; LANDMARK_COUNT];
        for (slot, &v) in landmarks.iter_mut().zip(&indices.idx_to_landmark_verts) {
            if v < 0 || v as usize >= n {
                return Err(indices_error(
                    &indices_path,
                    format!("landmark vertex {v} outside the mesh's 0..{n}"),
                ));
            }
            *slot = v as u32;
        }

        let identity_names: Vec<String> = (0..)
            .map(|i| format!("identity{i:03}"))
            .take_while(|name| dir.join(format!("{name}.obj")).is_file())
            .take(options.max_identities.unwrap_or(usize::MAX))
            .collect();
        let expression_names: Vec<String> = match &options.expressions {
            Some(wanted) => {
                for name in wanted {
                    if !dir.join(format!("{name}.obj")).is_file() {
                        let available: Vec<&str> = indices
                            .expressions
                            .iter()
                            .filter(|e| dir.join(format!("{e}.obj")).is_file())
                            .map(String::as_str)
                            .collect();
                        return Err(MorphableError::UnknownExpression {
                            dir: dir.clone(),
                            name: name.clone(),
                            available: available.join(", "),
                        });
                    }
                }
                wanted.clone()
            }
            None => indices
                .expressions
                .iter()
                .filter(|e| dir.join(format!("{e}.obj")).is_file())
                .cloned()
                .collect(),
        };
        let read_mode = |name: &String| -> Result<Vec<[f64; 3]>, MorphableError> {
            let path = dir.join(format!("{name}.obj"));
            let positions = read_obj_with(&path, &ObjReadOptions::POSITIONS)?
                .mesh
                .vertices;
            if positions.len() != n {
                return Err(MorphableError::VertexCount {
                    path,
                    expected: n,
                    got: positions.len(),
                });
            }
            Ok(positions
                .iter()
                .zip(&neutral)
                .map(|(p, q)| std::array::from_fn(|c| p[c] * CM_TO_M - q[c]))
                .collect())
        };
        let identity_modes = identity_names
            .par_iter()
            .map(read_mode)
            .collect::<Result<Vec<_>, _>>()?;
        let expression_modes = expression_names
            .par_iter()
            .map(read_mode)
            .collect::<Result<Vec<_>, _>>()?;
        Ok(IctModel {
            dir,
            neutral,
            triangles,
            triangle_polygon,
            identity_names,
            identity_modes,
            expression_names,
            expression_modes,
            landmarks,
        })
    }

    /// The neutral mesh file the model was read from (its UVs and materials are read from it
    /// by those who need them).
    pub fn neutral_path(&self) -> PathBuf {
        self.dir.join(NEUTRAL_FILE)
    }

    /// Number of vertices #V.
    pub fn vertex_count(&self) -> usize {
        self.neutral.len()
    }

    /// Index of the expression called `name`, if imported.
    pub fn expression_index(&self, name: &str) -> Option<usize> {
        self.expression_names.iter().position(|e| e == name)
    }

    /// The triangles whose three vertices all lie below `vertex_end` (e.g.
    /// [`crate::SOLID_SURFACE_END`]), in model order.
    pub fn triangles_below(&self, vertex_end: usize) -> Vec<[u32; 3]> {
        self.triangles
            .iter()
            .filter(|t| t.iter().all(|&i| (i as usize) < vertex_end))
            .copied()
            .collect()
    }

    /// Writes `S = S̄ + Σ_i identity[i] U_i + Σ_j expression[j] B_j` (metres, model frame) into
    /// `out` (resized to #V). Weights are used as given (no clamping).
    ///
    /// # Errors
    /// A weight vector whose length differs from the number of imported modes.
    pub fn shape(
        &self,
        identity: &[f64],
        expression: &[f64],
        out: &mut Vec<[f64; 3]>,
    ) -> Result<(), MorphableError> {
        for (what, expected, got) in [
            ("identity", self.identity_modes.len(), identity.len()),
            ("expression", self.expression_modes.len(), expression.len()),
        ] {
            if expected != got {
                return Err(MorphableError::WeightCount {
                    what,
                    expected,
                    got,
                });
            }
        }
        out.clear();
        out.extend_from_slice(&self.neutral);
        let modes = self
            .identity_modes
            .iter()
            .zip(identity)
            .chain(self.expression_modes.iter().zip(expression));
        for (mode, &w) in modes {
            if w == 0.0 {
                continue;
            }
            for (p, d) in out.iter_mut().zip(mode) {
                for c in 0..3 {
                    p[c] += w * d[c];
                }
            }
        }
        Ok(())
    }
}
