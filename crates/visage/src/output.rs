//! [`OutputDir`]: a run's results as files — `meshes/NNNNNN.ply` (and `raw/`), a streamed
//! `landmarks.json`, `camera.json` and `metrics.json`. Every file appears complete or not at
//! all (written under a temporary name, then renamed); `landmarks.json` is valid JSON with the
//! frames so far even after a failure.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use visage_camera::Intrinsics;
use visage_mesh::io::{write_obj, write_ply_with, PlyFormat};
use visage_mesh::TriMesh;

use crate::animation::{BlendshapeFrame, BlendshapesJsonWriter, LiveLinkCsvWriter};
use crate::atomic_write::{tmp_path, write_atomically, write_json_atomically};
use crate::landmarks::LandmarksFrame;
use crate::reconstructor::Identity;
use crate::sink::{FrameSink, MeshFrame};
use crate::Error;

/// An output folder being written.
pub struct OutputDir {
    dir: PathBuf,
    save_raw: bool,
    format: PlyFormat,
    /// `landmarks.json.tmp` while the run goes on, and whether a frame was written yet.
    landmarks: Option<(BufWriter<File>, bool)>,
    blendshapes: Option<(LiveLinkCsvWriter, BlendshapesJsonWriter)>,
    mesh: TriMesh,
}

/// The frame rate of `blendshapes.csv`'s timecode when the input has none (an image folder).
pub const DEFAULT_TIMECODE_FPS: f64 = 30.0;

impl OutputDir {
    /// Creates `dir/meshes/` (and `dir/raw/` with `save_raw`).
    ///
    /// # Errors
    /// When the folders cannot be created.
    pub fn create(dir: &Path, save_raw: bool, format: PlyFormat) -> Result<OutputDir, Error> {
        for sub in ["meshes"].into_iter().chain(save_raw.then_some("raw")) {
            let path = dir.join(sub);
            std::fs::create_dir_all(&path).map_err(|source| Error::Write { path, source })?;
        }
        Ok(OutputDir {
            dir: dir.to_owned(),
            save_raw,
            format,
            landmarks: None,
            blendshapes: None,
            mesh: TriMesh::new(Vec::new(), Vec::new()),
        })
    }

    /// Starts `landmarks.json`: the frames' landmarks records go there from now on.
    ///
    /// # Errors
    /// When the file cannot be created.
    pub fn with_landmarks(mut self) -> Result<OutputDir, Error> {
        let tmp = tmp_path(&self.dir.join("landmarks.json"));
        let write_error = |source| Error::Write {
            path: tmp.clone(),
            source,
        };
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
        let csv = LiveLinkCsvWriter::in_dir(&self.dir, fps.unwrap_or(DEFAULT_TIMECODE_FPS))?;
        let json = BlendshapesJsonWriter::in_dir(&self.dir, fps)?;
        self.blendshapes = Some((csv, json));
        Ok(self)
    }

    /// Writes the fitted identity: `identity.obj` (the neutral face in metres, model frame,
    /// with UVs) and `identity.json` (the coefficients and how many frames they rest on).
    ///
    /// # Errors
    /// When a file cannot be written.
    pub fn write_identity(&self, identity: &Identity) -> Result<(), Error> {
        let path = self.dir.join("identity.obj");
        let mesh = identity.neutral_mesh();
        write_atomically(&path, |p| {
            write_obj(p, &mesh).map_err(|source| Error::WriteMesh {
                path: p.to_owned(),
                source,
            })
        })?;
        write_json_atomically(
            &self.dir.join("identity.json"),
            &serde_json::json!({
                "coefficients": identity.coefficients,
                "frames": identity.frames,
                "units": "weights of the model's identity modes, each ~ N(0, 1)",
            }),
        )
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Writes `camera.json`: the intrinsics the meshes are in.
    pub fn write_camera(&self, k: &Intrinsics) -> Result<(), Error> {
        write_json_atomically(&self.dir.join("camera.json"), k)
    }

    /// Writes `metrics.json`.
    pub fn write_metrics(&self, report: &impl serde::Serialize) -> Result<(), Error> {
        write_json_atomically(&self.dir.join("metrics.json"), report)
    }

    /// Closes `landmarks.json` and the blendshape files (also after a failed run: they then
    /// hold the frames so far).
    pub fn finish(&mut self) -> Result<(), Error> {
        if let Some((csv, json)) = self.blendshapes.take() {
            csv.finish()?;
            json.finish()?;
        }
        let Some((mut w, _)) = self.landmarks.take() else {
            return Ok(());
        };
        let path = self.dir.join("landmarks.json");
        let tmp = tmp_path(&path);
        w.write_all(b"]}\n")
            .and_then(|()| w.flush())
            .map_err(|source| Error::Write {
                path: tmp.clone(),
                source,
            })?;
        drop(w);
        std::fs::rename(&tmp, &path).map_err(|source| Error::Write { path, source })
    }
}

impl FrameSink for OutputDir {
    fn landmarks(&mut self, record: &LandmarksFrame) -> Result<(), Error> {
        let Some((w, started)) = &mut self.landmarks else {
            return Ok(());
        };
        let path = tmp_path(&self.dir.join("landmarks.json"));
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

    fn blendshapes(&mut self, frame: &BlendshapeFrame) -> Result<(), Error> {
        if let Some((csv, json)) = &mut self.blendshapes {
            csv.write(frame)?;
            json.write(frame)?;
        }
        Ok(())
    }

    fn mesh(&mut self, frame: &MeshFrame<'_>) -> Result<(), Error> {
        let name = format!("{:06}.ply", frame.index);
        let s = frame.surfaces;
        let targets = [("meshes", &s.fused, true), ("raw", &s.raw, self.save_raw)];
        if self.mesh.triangles != frame.triangles {
            self.mesh.triangles = frame.triangles.to_vec();
        }
        if self.mesh.uvs != frame.uvs {
            self.mesh.uvs = frame.uvs.to_vec();
        }
        for (sub, vertices, wanted) in targets {
            if !wanted {
                continue;
            }
            self.mesh.vertices.clear();
            self.mesh.vertices.extend_from_slice(vertices);
            let path = self.dir.join(sub).join(&name);
            write_atomically(&path, |p| {
                write_ply_with(p, &self.mesh, self.format).map_err(|source| Error::WriteMesh {
                    path: p.to_owned(),
                    source,
                })
            })?;
        }
        Ok(())
    }
}
