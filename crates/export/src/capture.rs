//! [`Capture`]: a finished run read back from its output folder — the camera, every processed
//! frame's surface (from the point cache), time, head pose and blendshape weights, and the run's
//! metrics — everything the exports are made from.

use std::path::{Path, PathBuf};

use serde_json::Value;
use visage_camera::{Intrinsics, RigidTransform};
use visage_mesh::io::{read_obj, read_pc2};
use visage_mesh::TriMesh;
use visage_run_folder::file_names;

use crate::ExportError;

/// One processed frame.
#[derive(Clone, Debug)]
pub struct CaptureFrame {
    /// Input frame index.
    pub index: usize,
    /// Seconds since the input's first frame.
    pub time_s: f64,
    /// Whether the frame has its own mesh (otherwise the point cache holds a neighbour's).
    pub meshed: bool,
    /// Head → camera (the metric face fit), when a face was fitted.
    pub pose: Option<RigidTransform>,
}

/// The ARKit blendshape curves of a run (`blendshapes.json`).
#[derive(Clone, Debug)]
pub struct Blendshapes {
    /// ARKit's camelCase names.
    pub names: Vec<String>,
    /// Per processed frame (as [`Capture::frames`]), the weights; `None` where the frame has
    /// none.
    pub weights: Vec<Option<Vec<f32>>>,
    /// Per processed frame, the head's yaw, pitch and roll (radians, Live Link Face's angles);
    /// `None` where the frame has none.
    pub head: Vec<Option<[f32; 3]>>,
}

/// A run's output folder, read back.
pub struct Capture {
    pub dir: PathBuf,
    /// The camera the surfaces are in.
    pub intrinsics: Intrinsics,
    /// The input the run read (as `metrics.json` names it).
    pub input: PathBuf,
    /// The mesh: triangles and UVs (its vertices are the first meshed frame's, camera
    /// coordinates).
    pub mesh: TriMesh,
    pub frames: Vec<CaptureFrame>,
    /// Every frame's surface, camera coordinates (metres), `3 × vertices` values a frame.
    pub surfaces: Vec<f32>,
    pub blendshapes: Option<Blendshapes>,
    /// `metrics.json` as written.
    pub metrics: Value,
}

impl Capture {
    /// Reads `dir`: `camera.json`, `metrics.json`, `mesh.obj`, `sequence.pc2` and, when
    /// present, `blendshapes.json`.
    ///
    /// # Errors
    /// A missing or malformed file (named), or files that do not belong together (a point cache
    /// with another number of frames or vertices than the metrics and the mesh say).
    pub fn open(dir: &Path) -> Result<Capture, ExportError> {
        check_run_folder(dir)?;
        let intrinsics = Intrinsics::load_json(&dir.join(file_names::CAMERA))?;
        let metrics_path = dir.join(file_names::METRICS);
        let metrics = read_json(&metrics_path)?;
        // By its absolute path where the run recorded one (the typed one may be relative to
        // another working folder).
        let input = PathBuf::from(
            metrics["input_file"]["path"]
                .as_str()
                .or(metrics["input"].as_str())
                .unwrap_or_default(),
        );
        let obj = dir.join(file_names::CACHE_MESH);
        let mut mesh = read_obj(&obj)?;
        let cache_path = dir.join(file_names::POINT_CACHE);
        let cache = read_pc2(&cache_path)?;
        let frames = parse_frames(&metrics, &metrics_path)?;
        let mismatch = |reason: String| ExportError::Mismatch {
            path: cache_path.clone(),
            reason,
        };
        if cache.points != mesh.vertices.len() {
            return Err(mismatch(format!(
                "{} points a frame, {} has {} vertices",
                cache.points,
                obj.display(),
                mesh.vertices.len()
            )));
        }
        if cache.samples() != frames.len() {
            return Err(mismatch(format!(
                "{} frames, {} lists {}",
                cache.samples(),
                metrics_path.display(),
                frames.len()
            )));
        }
        // The files' y-up axes (x, −y, −z) back to the camera's (a half turn is its own
        // inverse).
        let mut surfaces = cache.positions;
        for p in surfaces.chunks_exact_mut(3) {
            p[1] = -p[1];
            p[2] = -p[2];
        }
        mesh.vertices = first_meshed(&frames, &surfaces)
            .chunks_exact(3)
            .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
            .collect();
        let blendshapes_path = dir.join(file_names::BLENDSHAPES_JSON);
        let blendshapes = if blendshapes_path.is_file() {
            Some(parse_blendshapes(
                &read_json(&blendshapes_path)?,
                &frames,
                &blendshapes_path,
            )?)
        } else {
            None
        };
        Ok(Capture {
            dir: dir.to_owned(),
            intrinsics,
            input,
            mesh,
            frames,
            surfaces,
            blendshapes,
            metrics,
        })
    }

    /// Vertices per frame.
    pub fn vertex_count(&self) -> usize {
        self.mesh.vertices.len()
    }

    /// Frame `k`'s surface (`k` counts processed frames), `x, y, z` per vertex.
    pub fn surface(&self, k: usize) -> &[f32] {
        let n = 3 * self.vertex_count();
        &self.surfaces[n * k..n * (k + 1)]
    }

    /// Frame `k`'s surface as `f64` points.
    pub fn surface_points(&self, k: usize) -> Vec<[f64; 3]> {
        self.surface(k)
            .chunks_exact(3)
            .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
            .collect()
    }

    /// The frames with a mesh of their own.
    pub fn meshed(&self) -> impl Iterator<Item = (usize, &CaptureFrame)> {
        self.frames.iter().enumerate().filter(|(_, f)| f.meshed)
    }
}

/// A JSON file, errors naming it.
pub(crate) fn read_json(path: &Path) -> Result<Value, ExportError> {
    let text = std::fs::read_to_string(path).map_err(|source| ExportError::Read {
        path: path.to_owned(),
        source,
    })?;
    serde_json::from_str(&text).map_err(|e| ExportError::Malformed {
        path: path.to_owned(),
        reason: e.to_string(),
    })
}

/// Says what `dir` is when it is not a run that can be exported: no folder, a folder no run
/// wrote to, a run over every face (its faces are the runs), a run killed before it finished.
fn check_run_folder(dir: &Path) -> Result<(), ExportError> {
    let not_a_run = |reason: String| {
        Err(ExportError::NotARun {
            dir: dir.to_owned(),
            reason,
        })
    };
    if !dir.is_dir() {
        return not_a_run("no such folder".into());
    }
    let contents = visage_run_folder::inspect(dir).map_err(|e| ExportError::Read {
        path: dir.to_owned(),
        source: std::io::Error::other(e.to_string()),
    })?;
    if dir.join(file_names::FACES).is_file() && !dir.join(file_names::METRICS).is_file() {
        return not_a_run(format!(
            "a run over every face: each face's run is in its own folder ({}1, {}2, …); \
             export those",
            file_names::FACE_FOLDER_PREFIX,
            file_names::FACE_FOLDER_PREFIX
        ));
    }
    if !contents.written_by_visage() {
        return not_a_run(format!(
            "not a visage run folder (it has no {}): `visage run INPUT --out` into it makes \
             one, then export",
            file_names::METRICS
        ));
    }
    if contents.status.as_deref() == Some("running") {
        return not_a_run(format!(
            "the run there was killed before it finished ({} says \"running\"); finish it \
             with the same `visage run` command and --resume, then export",
            file_names::METRICS
        ));
    }
    Ok(())
}

fn parse_frames(metrics: &Value, path: &Path) -> Result<Vec<CaptureFrame>, ExportError> {
    let malformed = |reason: String| ExportError::Malformed {
        path: path.to_owned(),
        reason,
    };
    let list = metrics["frames"]
        .as_array()
        .ok_or_else(|| malformed("no \"frames\" list".into()))?;
    let fps = metrics["parameters"]["frame_rate"].as_f64().unwrap_or(30.0);
    let mut frames = Vec::with_capacity(list.len());
    for (k, f) in list.iter().enumerate() {
        let index = f["index"]
            .as_u64()
            .ok_or_else(|| malformed(format!("frame {k}: no index")))? as usize;
        let status = f["status"].as_str().unwrap_or_default();
        let pose = match f.get("pose") {
            Some(p) if !p.is_null() => Some(
                parse_pose(p).ok_or_else(|| malformed(format!("frame {index}: malformed pose")))?,
            ),
            _ => None,
        };
        frames.push(CaptureFrame {
            index,
            time_s: f["time_s"].as_f64().unwrap_or(index as f64 / fps),
            meshed: matches!(status, "solved" | "carried"),
            pose,
        });
    }
    Ok(frames)
}

fn parse_pose(p: &Value) -> Option<RigidTransform> {
    let rows = p["rotation"].as_array()?;
    let mut rotation = [[0.0; 3]; 3];
    for (r, row) in rows.iter().take(3).enumerate() {
        for (c, v) in row.as_array()?.iter().take(3).enumerate() {
            rotation[r][c] = v.as_f64()?;
        }
    }
    let t = p["translation_m"].as_array()?;
    let translation = [
        t.first()?.as_f64()?,
        t.get(1)?.as_f64()?,
        t.get(2)?.as_f64()?,
    ];
    Some(RigidTransform {
        rotation,
        translation,
    })
}

fn parse_blendshapes(
    json: &Value,
    frames: &[CaptureFrame],
    path: &Path,
) -> Result<Blendshapes, ExportError> {
    let malformed = |reason: &str| ExportError::Malformed {
        path: path.to_owned(),
        reason: reason.into(),
    };
    let names: Vec<String> = json["names"]
        .as_array()
        .ok_or_else(|| malformed("no \"names\" list"))?
        .iter()
        .map(|n| n.as_str().unwrap_or_default().to_owned())
        .collect();
    let mut by_index = std::collections::HashMap::new();
    for f in json["frames"].as_array().into_iter().flatten() {
        let (Some(index), Some(w)) = (f["index"].as_u64(), f["weights"].as_array()) else {
            return Err(malformed("a frame without index or weights"));
        };
        let w: Vec<f32> = w.iter().map(|v| v.as_f64().unwrap_or(0.0) as f32).collect();
        if w.len() != names.len() {
            return Err(malformed("a frame's weights do not match the names"));
        }
        let head = f["head"].as_array().and_then(|h| {
            let angle = |i: usize| Some(h.get(i)?.as_f64()? as f32);
            Some([angle(0)?, angle(1)?, angle(2)?])
        });
        by_index.insert(index as usize, (w, head));
    }
    let (weights, head) = frames
        .iter()
        .map(|f| match by_index.remove(&f.index) {
            Some((w, head)) => (Some(w), head),
            None => (None, None),
        })
        .unzip();
    Ok(Blendshapes {
        names,
        weights,
        head,
    })
}

/// The first meshed frame's surface (the first frame's when none is).
fn first_meshed<'a>(frames: &[CaptureFrame], surfaces: &'a [f32]) -> &'a [f32] {
    let k = frames.iter().position(|f| f.meshed).unwrap_or(0);
    let n = surfaces.len() / frames.len().max(1);
    &surfaces[n * k..n * (k + 1)]
}

/// A capture of `n` meshed frames at 30 fps over a one-triangle mesh, for tests.
#[cfg(test)]
pub(crate) fn synthetic(n: usize, metrics: Value, blendshapes: Option<Blendshapes>) -> Capture {
    Capture {
        dir: PathBuf::new(),
        intrinsics: Intrinsics {
            width: 64,
            height: 64,
            fx: 60.0,
            fy: 60.0,
            cx: 32.0,
            cy: 32.0,
        },
        input: PathBuf::new(),
        mesh: TriMesh::new(vec![[0.0; 3]; 3], vec![[0, 1, 2]]),
        frames: (0..n)
            .map(|index| CaptureFrame {
                index,
                time_s: index as f64 / 30.0,
                meshed: true,
                pose: None,
            })
            .collect(),
        surfaces: vec![0.0; 9 * n],
        blendshapes,
        metrics,
    }
}
