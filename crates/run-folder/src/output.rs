//! [`OutputDir`]: a run's results as files — the surface per frame as a point cache
//! (`sequence.pc2` with `mesh.obj` and `mesh.mtl`, the layout Blender's Mesh Cache modifier
//! plays) and/or `meshes/NNNNNN.ply` (and `raw/`), a streamed `landmarks.json`, `camera.json`
//! and `metrics.json`. Every file appears complete or not at all (written under a temporary
//! name, then renamed); `landmarks.json` is valid JSON with the frames so far even after a
//! failure.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use visage_camera::Intrinsics;
use visage_mesh::io::{
    read_pc2, write_mtl, write_obj, write_obj_with, write_ply_with, MeshIoError, ObjMaterial,
    Pc2Writer, PlyFormat,
};
use visage_mesh::TriMesh;

use visage_rig::BlendshapeFrame;

use crate::atomic_write::{tmp_path, write_atomically, write_json_atomically};
use crate::blendshapes_json::BlendshapesJsonWriter;
use crate::file_names;
use crate::landmarks::LandmarksFrame;
use crate::live_link_csv::LiveLinkCsvWriter;
use crate::resume_point::{ResumePoint, RunDescription, RunParameters};
use crate::stream::{Completed, Stream};
use crate::RunFolderError as Error;

/// An output folder being written.
pub struct OutputDir {
    dir: PathBuf,
    /// PLY per frame: the format, and whether the fused and the raw surfaces are wanted.
    ply: Option<(PlyFormat, bool, bool)>,
    /// The point cache, once its first frame came (or `Pending` until then).
    cache: PointCacheState,
    /// `landmarks.json.tmp` while the run goes on, and whether a frame was written yet.
    landmarks: Option<(BufWriter<File>, bool)>,
    blendshapes: Option<(LiveLinkCsvWriter, BlendshapesJsonWriter)>,
    mesh: TriMesh,
    /// Input indices of every frame so far (from the landmarks records).
    frames: Vec<usize>,
    /// One frame's surface in the y-up axes.
    y_up: Vec<[f64; 3]>,
    /// A resumed run: the streamed files continue from here ([`OutputDir::resuming`]).
    resume: Option<ResumePoint>,
    /// Whether a frame's write failed: the streams may end inside a record, so
    /// [`OutputDir::finish`] leaves them under their temporary names.
    failed: bool,
}

/// `sequence.pc2` being written: one sample per meshed frame as they come; frames without a
/// mesh get the held surface when the cache is finished.
enum PointCacheState {
    Off,
    Pending,
    Writing {
        writer: Pc2Writer,
        /// Input indices of the frames written, in order.
        meshed: Vec<usize>,
    },
}

/// The material's name in it.
pub const CACHE_MATERIAL: &str = "face";

/// Camera coordinates (x right, y down, z forward) → the y-up coordinates of OBJ, PC2 and glTF
/// files (x right, y up, the camera looking down −z): a half turn about x.
pub fn camera_to_y_up(p: [f64; 3]) -> [f64; 3] {
    [p[0], -p[1], -p[2]]
}

/// The frame rate of `blendshapes.csv`'s timecode when the input has none (an image folder).
pub const DEFAULT_TIMECODE_FPS: f64 = 30.0;

impl OutputDir {
    /// Creates the folder; no file is written until a `with_…` asks for it.
    ///
    /// # Errors
    /// When the folder cannot be created.
    pub fn create(dir: &Path) -> Result<OutputDir, Error> {
        std::fs::create_dir_all(dir).map_err(|source| Error::Write {
            path: dir.to_owned(),
            source,
        })?;
        Ok(OutputDir {
            dir: dir.to_owned(),
            ply: None,
            cache: PointCacheState::Off,
            landmarks: None,
            blendshapes: None,
            mesh: TriMesh::new(Vec::new(), Vec::new()),
            frames: Vec::new(),
            y_up: Vec::new(),
            resume: None,
            failed: false,
        })
    }

    /// Continues a run that stopped part-way, from the files [`crate::prepare_resume`] cut
    /// back to `point`: the `with_…` calls that follow append to the streamed files rather than
    /// starting them, and the frames up to the resume point (the warm-up) are not written
    /// again.
    pub fn resuming(mut self, point: ResumePoint) -> OutputDir {
        self.resume = Some(point);
        self
    }

    /// A PLY per meshed frame: the fused surface in `meshes/` (with `fused`) and the raw one
    /// in `raw/` (with `raw`).
    ///
    /// # Errors
    /// When the folders cannot be created.
    pub fn with_ply(
        mut self,
        format: PlyFormat,
        fused: bool,
        raw: bool,
    ) -> Result<OutputDir, Error> {
        for (sub, wanted) in [
            (file_names::MESHES_FOLDER, fused),
            (file_names::RAW_FOLDER, raw),
        ] {
            if wanted {
                let path = self.dir.join(sub);
                std::fs::create_dir_all(&path).map_err(|source| Error::Write { path, source })?;
            }
        }
        self.ply = Some((format, fused, raw));
        Ok(self)
    }

    /// The fused surface as a point cache: `sequence.pc2` (one sample per processed frame,
    /// frames without a mesh holding the nearest earlier one, or the first) beside `mesh.obj`
    /// (the first meshed frame, with UVs) and `mesh.mtl`, both in the y-up axes of
    /// [`camera_to_y_up`]. Blender's OBJ importer keeps a file's numbers in the mesh and puts
    /// its axis change on the object, and the Mesh Cache modifier writes mesh coordinates, so
    /// the cache holds the same numbers as the OBJ's `v` lines.
    ///
    /// # Errors
    /// A resumed run whose point cache cannot be continued.
    pub fn with_point_cache(mut self) -> Result<OutputDir, Error> {
        self.cache = match &self.resume {
            Some(point) if !point.cache_indices.is_empty() => {
                let tmp = tmp_path(&self.dir.join(file_names::POINT_CACHE));
                let samples = u32::try_from(point.cache_indices.len()).unwrap_or(u32::MAX);
                let writer =
                    Pc2Writer::append(&tmp, samples).map_err(|source| Error::WriteMesh {
                        path: tmp.clone(),
                        source,
                    })?;
                PointCacheState::Writing {
                    writer,
                    meshed: point.cache_indices.clone(),
                }
            }
            _ => PointCacheState::Pending,
        };
        Ok(self)
    }

    /// Starts `landmarks.json`: the frames' landmarks records go there from now on.
    ///
    /// # Errors
    /// When the file cannot be created.
    pub fn with_landmarks(mut self) -> Result<OutputDir, Error> {
        let tmp = tmp_path(&self.dir.join(file_names::LANDMARKS));
        let write_error = |source| Error::Write {
            path: tmp.clone(),
            source,
        };
        if let Some(point) = &self.resume {
            let file = std::fs::OpenOptions::new()
                .append(true)
                .open(&tmp)
                .map_err(write_error)?;
            self.frames = point.frame_indices.clone();
            self.landmarks = Some((BufWriter::new(file), point.frames > 0));
            return Ok(self);
        }
        let mut w = BufWriter::new(File::create(&tmp).map_err(write_error)?);
        w.write_all(b"{\"frames\": [").map_err(write_error)?;
        self.landmarks = Some((w, false));
        Ok(self)
    }

    /// Starts `blendshapes.csv` (Live Link Face's layout, timecode at `fps`, else
    /// [`DEFAULT_TIMECODE_FPS`]) and `blendshapes.json`.
    ///
    /// # Errors
    /// When the files cannot be created.
    pub fn with_blendshapes(mut self, fps: Option<f64>) -> Result<OutputDir, Error> {
        let timecode_fps = fps.unwrap_or(DEFAULT_TIMECODE_FPS);
        let (csv, json) = match &self.resume {
            Some(point) => (
                LiveLinkCsvWriter::append_in_dir(&self.dir, timecode_fps, point.blendshape_frames)?,
                BlendshapesJsonWriter::append_in_dir(&self.dir, point.blendshape_frames)?,
            ),
            None => (
                LiveLinkCsvWriter::in_dir(&self.dir, timecode_fps)?,
                BlendshapesJsonWriter::in_dir(&self.dir, fps)?,
            ),
        };
        self.blendshapes = Some((csv, json));
        Ok(self)
    }

    /// Writes the fitted identity: `identity.obj` (the neutral face in metres, model frame,
    /// with UVs) and `identity.json` (the coefficients and how many frames they rest on).
    ///
    /// # Errors
    /// When a file cannot be written.
    pub fn write_identity(
        &self,
        neutral: &TriMesh,
        coefficients: &[f64],
        frames: usize,
    ) -> Result<(), Error> {
        let path = self.dir.join(file_names::IDENTITY_MESH);
        write_atomically(&path, |p| {
            write_obj(p, neutral).map_err(|source| Error::WriteMesh {
                path: p.to_owned(),
                source,
            })
        })?;
        write_json_atomically(
            &self.dir.join(file_names::IDENTITY),
            &serde_json::json!({
                "coefficients": coefficients,
                "frames": frames,
                "units": "weights of the model's identity modes, each ~ N(0, 1)",
            }),
        )
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Writes `camera.json`: the intrinsics the meshes are in.
    pub fn write_camera(&self, k: &Intrinsics) -> Result<(), Error> {
        write_json_atomically(&self.dir.join(file_names::CAMERA), k)
    }

    /// Writes the `metrics.json` of a run that has started: `"status": "running"`, the input,
    /// the camera, the parameters and the frame selection, and where a resumed run continues
    /// (the final one replaces it).
    pub fn write_running<P: RunParameters>(
        &self,
        run: &RunDescription<'_, P>,
    ) -> Result<(), Error> {
        let mut metrics = serde_json::json!({ "status": crate::RunStatus::Running });
        if let (Some(m), Ok(serde_json::Value::Object(run))) =
            (metrics.as_object_mut(), serde_json::to_value(run))
        {
            m.extend(run);
            if let Some(point) = &self.resume {
                m.insert("resumed".into(), serde_json::json!(point));
            }
        }
        self.write_metrics(&metrics)
    }

    /// Writes `metrics.json`.
    pub fn write_metrics(&self, report: &impl serde::Serialize) -> Result<(), Error> {
        write_json_atomically(&self.dir.join(file_names::METRICS), report)
    }

    /// Whether a frame's write failed (the streams then stay under their temporary names).
    pub fn write_failed(&self) -> bool {
        self.failed
    }

    /// The frames the files hold: every frame whose landmarks record was written (with a
    /// resumed run's kept frames).
    pub fn frames_written(&self) -> usize {
        self.frames.len()
    }

    /// Finishes the streamed files — the point cache, `landmarks.json` and the blendshape
    /// files — all or none: each is written to its end under its temporary name, and only when
    /// every one is are they renamed to their final names. After a failed frame write, or when
    /// one cannot be finished (a full disk), every file stays under its temporary name with
    /// the frames it held, and `visage run --resume` goes on from there.
    ///
    /// # Errors
    /// The first file that could not be finished (the run's earlier write error is its own).
    pub fn finish(&mut self) -> Result<(), Error> {
        if self.failed {
            return Ok(());
        }
        let mut completed = Vec::new();
        let mut first_error = None;
        let mut note = |result: Result<Option<Completed>, Error>| match result {
            Ok(done) => completed.extend(done),
            Err(e) => {
                first_error.get_or_insert(e);
            }
        };
        note(self.complete_landmarks());
        if let Some((csv, json)) = self.blendshapes.take() {
            note(csv.complete().map(Some));
            note(json.complete().map(Some));
        }
        let cache = self.complete_point_cache();
        if let Some(e) = first_error {
            for c in completed {
                let _ = c.withdraw();
            }
            if let Ok(Some(filled)) = cache {
                filled.withdraw();
            }
            return Err(e);
        }
        let cache = match cache {
            Ok(cache) => cache,
            Err(e) => {
                for c in completed {
                    let _ = c.withdraw();
                }
                return Err(e);
            }
        };
        if let Some(filled) = cache {
            filled.publish()?;
        }
        for c in completed {
            c.publish()?;
        }
        Ok(())
    }

    fn complete_landmarks(&mut self) -> Result<Option<Completed>, Error> {
        let Some((w, _)) = self.landmarks.take() else {
            return Ok(None);
        };
        let path = self.dir.join(file_names::LANDMARKS);
        Stream::from_writer(&path, w).complete(b"]}\n").map(Some)
    }
}

impl OutputDir {
    /// Hands everything streamed so far to the operating system.
    fn flush_streams(&mut self) -> Result<(), Error> {
        if let Some((w, _)) = &mut self.landmarks {
            w.flush().map_err(|source| Error::Write {
                path: tmp_path(&self.dir.join(file_names::LANDMARKS)),
                source,
            })?;
        }
        if let Some((csv, json)) = &mut self.blendshapes {
            csv.flush()?;
            json.flush()?;
        }
        if let PointCacheState::Writing { writer, .. } = &mut self.cache {
            writer.flush().map_err(|source| Error::WriteMesh {
                path: tmp_path(&self.dir.join(file_names::POINT_CACHE)),
                source,
            })?;
        }
        Ok(())
    }

    /// Starts the point cache on the first meshed frame: `mesh.obj`, `mesh.mtl` and the cache.
    fn start_point_cache(&mut self, vertices: &[[f64; 3]]) -> Result<(), Error> {
        let mesh_error = |path: &Path| {
            let path = path.to_owned();
            move |source| Error::WriteMesh { path, source }
        };
        let mut mesh = self.mesh.clone();
        mesh.vertices = vertices.iter().map(|&p| camera_to_y_up(p)).collect();
        let material = ObjMaterial {
            library: file_names::CACHE_MATERIAL_FILE,
            name: CACHE_MATERIAL,
        };
        write_atomically(&self.dir.join(file_names::CACHE_MESH), |p| {
            write_obj_with(p, &mesh, Some(material)).map_err(mesh_error(p))
        })?;
        write_atomically(&self.dir.join(file_names::CACHE_MATERIAL_FILE), |p| {
            write_mtl(p, CACHE_MATERIAL, None).map_err(mesh_error(p))
        })?;
        let tmp = tmp_path(&self.dir.join(file_names::POINT_CACHE));
        let writer = Pc2Writer::create(&tmp, vertices.len(), 0.0).map_err(mesh_error(&tmp))?;
        self.cache = PointCacheState::Writing {
            writer,
            meshed: Vec::new(),
        };
        Ok(())
    }

    /// Completes the point cache: its header's sample count, and when some frames have no
    /// mesh (every processed frame has a landmarks record), a copy with every frame filled
    /// (`sequence.pc2.filled.tmp`), the unfilled one staying for a resume until the copy is
    /// renamed into place.
    fn complete_point_cache(&mut self) -> Result<Option<FilledCache>, Error> {
        let PointCacheState::Writing { writer, meshed } =
            std::mem::replace(&mut self.cache, PointCacheState::Off)
        else {
            return Ok(None);
        };
        let path = self.dir.join(file_names::POINT_CACHE);
        let tmp = tmp_path(&path);
        let mesh_error = |path: &Path| {
            let path = path.to_owned();
            move |source: MeshIoError| Error::WriteMesh { path, source }
        };
        writer.finish().map_err(mesh_error(&tmp))?;
        let frames = &self.frames;
        if frames.is_empty() || *frames == meshed {
            return Ok(Some(FilledCache {
                source: tmp.clone(),
                unfilled: tmp,
                path,
            }));
        }
        let filled_path = self.dir.join(file_names::POINT_CACHE_FILLED);
        let fill = || {
            let cache = read_pc2(&tmp).map_err(mesh_error(&tmp))?;
            let mut filled = Pc2Writer::create(&filled_path, cache.points, 0.0)
                .map_err(mesh_error(&filled_path))?;
            let mut sample = 0;
            let mut points = vec![[0.0; 3]; cache.points];
            for &index in frames {
                while sample + 1 < meshed.len() && meshed[sample + 1] <= index {
                    sample += 1;
                }
                for (p, c) in points.iter_mut().zip(cache.sample(sample).chunks_exact(3)) {
                    *p = [c[0] as f64, c[1] as f64, c[2] as f64];
                }
                filled.push(&points).map_err(mesh_error(&filled_path))?;
            }
            filled.finish().map_err(mesh_error(&filled_path))
        };
        if let Err(e) = fill() {
            let _ = std::fs::remove_file(&filled_path);
            return Err(e);
        }
        Ok(Some(FilledCache {
            source: filled_path,
            unfilled: tmp,
            path,
        }))
    }
}

/// The point cache written to its end, not yet in place: `source` (the unfilled temporary
/// cache, or its filled copy) becomes `path`.
struct FilledCache {
    source: PathBuf,
    unfilled: PathBuf,
    path: PathBuf,
}

impl FilledCache {
    fn publish(self) -> Result<(), Error> {
        std::fs::rename(&self.source, &self.path).map_err(|source| Error::Write {
            path: self.path.clone(),
            source,
        })?;
        if self.source != self.unfilled {
            let _ = std::fs::remove_file(&self.unfilled);
        }
        Ok(())
    }

    /// Leaves the unfilled temporary cache, for a resume.
    fn withdraw(self) {
        if self.source != self.unfilled {
            let _ = std::fs::remove_file(&self.source);
        }
    }
}

impl OutputDir {
    /// Whether frame `index` was written by the run this one resumes (a warm-up frame).
    fn written_before(&self, index: usize) -> bool {
        self.resume.as_ref().is_some_and(|p| index <= p.after_frame)
    }
}

/// A meshed frame's surfaces, as [`OutputDir::write_mesh`] stores them.
#[derive(Clone, Copy, Debug)]
pub struct MeshOutput<'a> {
    /// Frame index in the input.
    pub index: usize,
    /// The mesh's triangles (fixed for the run).
    pub triangles: &'a [[u32; 3]],
    /// Texture coordinates per vertex (empty: the mesh has none).
    pub uvs: &'a [[f64; 2]],
    /// The fused surface (camera coordinates, metres).
    pub fused: &'a [[f64; 3]],
    /// The raw (unfused) surface on the same mesh.
    pub raw: &'a [[f64; 3]],
}

/// The streams, frame by frame, in input order. Frames up to a resumed run's resume point
/// (its warm-up) are skipped.
impl OutputDir {
    /// Appends a frame's landmarks record, after flushing every other stream.
    pub fn write_landmarks(&mut self, record: &LandmarksFrame) -> Result<(), Error> {
        let result = self.write_landmarks_unchecked(record);
        self.failed |= result.is_err();
        result
    }

    fn write_landmarks_unchecked(&mut self, record: &LandmarksFrame) -> Result<(), Error> {
        if self.written_before(record.index) {
            return Ok(());
        }
        // The earlier frames' outputs reach the operating system before this frame's record:
        // after a kill, every stream holds every frame before the last landmarks record
        // ([`crate::prepare_resume`]).
        self.flush_streams()?;
        self.frames.push(record.index);
        let Some((w, started)) = &mut self.landmarks else {
            return Ok(());
        };
        let path = tmp_path(&self.dir.join(file_names::LANDMARKS));
        let write_error = |source| Error::Write {
            path: path.clone(),
            source,
        };
        if *started {
            w.write_all(b",").map_err(write_error)?;
        }
        *started = true;
        serde_json::to_writer(&mut *w, record).map_err(|e| write_error(e.into()))
    }

    /// Appends a frame's blendshapes to the CSV and the JSON.
    pub fn write_blendshapes(&mut self, frame: &BlendshapeFrame) -> Result<(), Error> {
        let result = self.write_blendshapes_unchecked(frame);
        self.failed |= result.is_err();
        result
    }

    fn write_blendshapes_unchecked(&mut self, frame: &BlendshapeFrame) -> Result<(), Error> {
        if self.written_before(frame.index) {
            return Ok(());
        }
        if let Some((csv, json)) = &mut self.blendshapes {
            csv.write(frame)?;
            json.write(frame)?;
        }
        Ok(())
    }

    /// Appends a meshed frame's fused surface to the point cache and writes its PLYs.
    pub fn write_mesh(&mut self, frame: &MeshOutput<'_>) -> Result<(), Error> {
        let result = self.write_mesh_unchecked(frame);
        self.failed |= result.is_err();
        result
    }

    fn write_mesh_unchecked(&mut self, frame: &MeshOutput<'_>) -> Result<(), Error> {
        if self.written_before(frame.index) {
            return Ok(());
        }
        let name = format!("{:06}.ply", frame.index);
        if self.mesh.triangles != frame.triangles {
            self.mesh.triangles = frame.triangles.to_vec();
        }
        if self.mesh.uvs != frame.uvs {
            self.mesh.uvs = frame.uvs.to_vec();
        }
        if matches!(self.cache, PointCacheState::Pending) {
            self.start_point_cache(frame.fused)?;
        }
        if let PointCacheState::Writing { writer, meshed } = &mut self.cache {
            self.y_up.clear();
            self.y_up
                .extend(frame.fused.iter().map(|&p| camera_to_y_up(p)));
            writer.push(&self.y_up).map_err(|source| Error::WriteMesh {
                path: tmp_path(&self.dir.join(file_names::POINT_CACHE)),
                source,
            })?;
            meshed.push(frame.index);
        }
        let Some((format, fused, raw)) = self.ply else {
            return Ok(());
        };
        for (sub, vertices, wanted) in [
            (file_names::MESHES_FOLDER, frame.fused, fused),
            (file_names::RAW_FOLDER, frame.raw, raw),
        ] {
            if !wanted {
                continue;
            }
            self.mesh.vertices.clear();
            self.mesh.vertices.extend_from_slice(vertices);
            let path = self.dir.join(sub).join(&name);
            write_atomically(&path, |p| {
                write_ply_with(p, &self.mesh, format).map_err(|source| Error::WriteMesh {
                    path: p.to_owned(),
                    source,
                })
            })?;
        }
        Ok(())
    }
}
