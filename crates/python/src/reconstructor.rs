//! The per-frame reconstructor over numpy frames (the package's `visage.Reconstructor`).
//!
//! A frame crosses as an `(H, W, 3)` uint8 RGB array, copied once into the frame the pipeline
//! owns (a C-contiguous array in one `memcpy`). Heavy results come back as numpy arrays; the
//! frame's record as the JSON `metrics.json` holds. Frames are processed with the GIL released:
//! two reconstructors run on two threads at once.

use std::path::PathBuf;
use std::sync::Mutex;

use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use visage::{Camera, Intrinsics, Irises};
use visage_video::Frame;

use crate::error::error;

/// The mesh's triangles and texture coordinates (fixed for a reconstructor).
type MeshTopology = (Vec<[u32; 3]>, Vec<[f64; 2]>);

/// The camera the reconstructor is built with, at the first frame (its size completes it).
enum CameraChoice {
    Auto,
    FovDeg(f64),
    /// `(fx, fy, cx, cy)`, pixels.
    Focal([f64; 4]),
    /// An intrinsics file (`visage run --intrinsics`), loaded.
    File(PathBuf, Intrinsics),
}

/// The per-frame reconstructor (see the package's `Reconstructor`).
#[pyclass(module = "visage._visage")]
pub struct NativeReconstructor {
    camera: CameraChoice,
    /// Frames the landmark smoother waits for (0: `process`; more: `push` and `end`).
    latency: usize,
    models: Option<PathBuf>,
    /// Made at the first frame (its size sets the camera). In a mutex: a Python object may be
    /// used from any thread (one at a time).
    inner: Mutex<Option<(visage::Reconstructor, u32, u32)>>,
    frames: usize,
    /// The mesh's triangles and UVs, once a frame had a mesh.
    mesh: Option<MeshTopology>,
}

/// What a frame's result hands back across the GIL.
struct Processed {
    index: usize,
    metrics: String,
    /// The first face's 468 landmarks, `[x, y]` pixels, flat.
    landmarks: Option<Vec<f32>>,
    irises: Option<Irises>,
    /// Its metric head pose: rotation and translation (metres), model → camera.
    pose: Option<([[f64; 3]; 3], [f64; 3])>,
    vertices: Option<Vec<f32>>,
    mesh: Option<MeshTopology>,
    weights: Option<Vec<f32>>,
    head: Option<[f32; 3]>,
    eyes: Option<[[f32; 3]; 2]>,
    /// The identity coefficients the fit has settled on by this frame.
    identity: Option<Vec<f64>>,
}

impl Processed {
    /// `r` copied out (the mesh's triangles and UVs when `mesh_wanted`); the identity is the
    /// caller's to add, once `r` no longer borrows the reconstructor.
    fn of(r: visage::FrameResult<'_>, mesh_wanted: bool) -> Processed {
        let face = r.landmarks.faces.first();
        Processed {
            index: r.index(),
            metrics: serde_json::to_string(r.metrics).unwrap_or_default(),
            landmarks: face.map(|f| {
                f.landmarks
                    .iter()
                    .flat_map(|p| [p[0] as f32, p[1] as f32])
                    .collect()
            }),
            irises: r.irises.copied(),
            pose: face
                .and_then(|f| f.pose.as_ref())
                .map(|p| (p.rotation, p.translation_m)),
            vertices: r.mesh().map(|m| {
                m.vertices
                    .iter()
                    .flat_map(|v| v.map(|x| x as f32))
                    .collect()
            }),
            mesh: r
                .mesh()
                .filter(|_| mesh_wanted)
                .map(|m| (m.triangles.clone(), m.uvs.clone())),
            weights: r.blendshapes.map(|b| b.weights.to_vec()),
            head: r.blendshapes.map(|b| b.head),
            eyes: r.blendshapes.map(|b| [b.left_eye, b.right_eye]),
            identity: None,
        }
    }
}

/// Rows of `(N, C)` float32 from a flat vector.
fn rows<'py>(py: Python<'py>, flat: Vec<f32>, columns: usize) -> PyResult<Bound<'py, PyAny>> {
    let n = flat.len() / columns;
    Ok(PyArray1::from_vec(py, flat)
        .reshape([n, columns])?
        .into_any())
}

/// The 468 landmarks with the 10 iris points after them (NaN where the irises are unknown),
/// `(478, 2)` float32.
fn with_irises(mut landmarks: Vec<f32>, irises: Option<Irises>) -> Vec<f32> {
    match irises {
        Some(eyes) => landmarks.extend(eyes.iter().flatten().flat_map(|p| p.map(|x| x as f32))),
        None => landmarks.extend(std::iter::repeat_n(f32::NAN, 2 * 2 * 5)),
    }
    landmarks
}

impl NativeReconstructor {
    /// The frame as the pipeline takes it (one copy), after the checks numpy cannot make.
    fn frame(&self, frame: &PyReadonlyArray3<'_, u8>, timestamp_s: Option<f64>) -> PyResult<Frame> {
        let shape = frame.shape().to_vec();
        if shape[2] != 3 {
            return Err(PyValueError::new_err(format!(
                "a frame is an (H, W, 3) uint8 RGB array; this one is {shape:?}"
            )));
        }
        let (height, width) = (shape[0] as u32, shape[1] as u32);
        if height == 0 || width == 0 {
            return Err(PyValueError::new_err(format!(
                "a frame is an (H, W, 3) uint8 RGB array; this one is {shape:?}: empty"
            )));
        }
        let pixels: Vec<u8> = match frame.as_slice() {
            Ok(s) => s.to_vec(),
            Err(_) => frame.as_array().iter().copied().collect(),
        };
        let image = image::RgbImage::from_raw(width, height, pixels)
            .ok_or_else(|| PyValueError::new_err("the frame's size does not match its data"))?;
        let index = self.frames;
        Ok(Frame {
            index,
            source: format!("frame {index}"),
            timestamp_s,
            image,
        })
    }

    /// The reconstructor for frames of `width × height` (made at the first frame); a frame of
    /// another size is refused.
    fn ensure_built(
        &self,
        inner: &mut Option<(visage::Reconstructor, u32, u32)>,
        (width, height): (u32, u32),
    ) -> PyResult<()> {
        if let Some((_, w, h)) = inner {
            if (*w, *h) != (width, height) {
                return Err(PyValueError::new_err(format!(
                    "frame {}: {width}×{height}, where this reconstructor's frames are {w}×{h} \
                     (make a new Reconstructor for another video)",
                    self.frames
                )));
            }
            return Ok(());
        }
        let camera = match &self.camera {
            CameraChoice::Auto => Camera::Auto,
            CameraChoice::FovDeg(fov) => Camera::FovDeg(*fov),
            CameraChoice::Focal([fx, fy, cx, cy]) => Camera::Intrinsics(
                Intrinsics::new(width, height, *fx, *fy, *cx, *cy)
                    .map_err(|e| PyValueError::new_err(format!("intrinsics: {e}")))?,
            ),
            CameraChoice::File(path, k) => {
                k.check_size(width, height).map_err(|e| {
                    error(format!(
                        "{}: intrinsics are for another image size than the frames \
                         ({width}×{height}): {e}",
                        path.display()
                    ))
                })?;
                Camera::Intrinsics(*k)
            }
        };
        let mut builder = visage::Reconstructor::builder()
            .latency(self.latency)
            .camera(camera);
        if let Some(dir) = &self.models {
            builder = builder.models_dir(dir);
        }
        let r = builder.build(width, height).map_err(error)?;
        *inner = Some((r, width, height));
        Ok(())
    }

    /// A result as the dict the package's `FrameResult` is made from.
    fn result_dict<'py>(
        &mut self,
        py: Python<'py>,
        out: Processed,
    ) -> PyResult<Bound<'py, PyDict>> {
        if self.mesh.is_none() {
            self.mesh = out.mesh;
        }
        let d = PyDict::new(py);
        d.set_item("index", out.index)?;
        d.set_item("metrics_json", out.metrics)?;
        let landmarks = out
            .landmarks
            .map(|l| rows(py, with_irises(l, out.irises), 2))
            .transpose()?;
        d.set_item("landmarks", landmarks)?;
        d.set_item("has_irises", out.irises.is_some())?;
        let pose = out.pose.map(|(rotation, translation)| {
            let mut m = [0.0f64; 16];
            for r in 0..3 {
                m[4 * r..4 * r + 3].copy_from_slice(&rotation[r]);
                m[4 * r + 3] = translation[r];
            }
            m[15] = 1.0;
            m
        });
        let pose = pose
            .map(|m| PyArray1::from_vec(py, m.to_vec()).reshape([4, 4]))
            .transpose()?;
        d.set_item("head_pose", pose)?;
        d.set_item(
            "vertices",
            out.vertices.map(|v| rows(py, v, 3)).transpose()?,
        )?;
        d.set_item("weights", out.weights.map(|w| PyArray1::from_vec(py, w)))?;
        d.set_item("head", out.head)?;
        d.set_item("eyes", out.eyes)?;
        d.set_item("identity", out.identity.map(|c| PyArray1::from_vec(py, c)))?;
        Ok(d)
    }

    /// `work` on the reconstructor (built for `frame`'s size if it is the first), with the GIL
    /// released; the results it gives as dicts.
    fn with_frame<'py>(
        &mut self,
        py: Python<'py>,
        frame: Option<Frame>,
        work: impl FnOnce(&mut visage::Reconstructor, Option<Frame>, bool) -> WorkResult + Send,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let given = frame.is_some();
        let results = {
            let mut inner = self.inner.lock().unwrap_or_else(|e| e.into_inner());
            match &frame {
                Some(f) => self.ensure_built(&mut inner, f.image.dimensions())?,
                None if inner.is_none() => return Ok(Vec::new()),
                None => {}
            }
            let (reconstructor, _, _) = inner.as_mut().expect("built above");
            let mesh_wanted = self.mesh.is_none();
            py.detach(|| work(reconstructor, frame, mesh_wanted))
        };
        if given {
            self.frames += 1;
        }
        let results = results.map_err(error)?;
        results
            .into_iter()
            .map(|out| self.result_dict(py, out))
            .collect()
    }
}

/// What the work on a frame gives: the results completed, or visage's error.
type WorkResult = Result<Vec<Processed>, visage::Error>;

/// Every result `push` or `push_end` completed, each with the identity after it.
fn drain(reconstructor: &mut visage::Reconstructor, mut mesh_wanted: bool) -> WorkResult {
    let mut done = Vec::new();
    while let Some(r) = reconstructor.next_result() {
        let mut p = Processed::of(r?, mesh_wanted);
        mesh_wanted &= p.mesh.is_none();
        p.identity = reconstructor.identity().map(|i| i.coefficients);
        done.push(p);
    }
    Ok(done)
}

#[pymethods]
impl NativeReconstructor {
    #[new]
    #[pyo3(signature = (fov_deg=None, intrinsics=None, intrinsics_file=None, mode="streaming",
        latency=0, models=None))]
    fn new(
        fov_deg: Option<f64>,
        intrinsics: Option<(f64, f64, f64, f64)>,
        intrinsics_file: Option<PathBuf>,
        mode: &str,
        latency: usize,
        models: Option<PathBuf>,
    ) -> PyResult<Self> {
        match mode {
            "streaming" => {}
            "clip" => {
                return Err(PyValueError::new_err(
                    "mode=\"clip\" solves the whole clip at once, which a frame-by-frame \
                     reconstructor cannot: visage.run(input, out_dir, mode=\"clip\") runs it",
                ))
            }
            other => {
                return Err(PyValueError::new_err(format!(
                    "mode={other:?}: must be \"streaming\" or \"clip\""
                )))
            }
        }
        if latency > visage::MAX_LATENCY_FRAMES {
            return Err(PyValueError::new_err(format!(
                "latency={latency}: at most {} frames",
                visage::MAX_LATENCY_FRAMES
            )));
        }
        let camera = match (fov_deg, intrinsics, intrinsics_file) {
            (None, None, None) => CameraChoice::Auto,
            (Some(fov), None, None) => {
                visage::check_fov(fov).map_err(|e| {
                    PyValueError::new_err(e.to_string().replace("--fov-deg", "fov_deg"))
                })?;
                CameraChoice::FovDeg(fov)
            }
            (None, Some((fx, fy, cx, cy)), None) => CameraChoice::Focal([fx, fy, cx, cy]),
            (None, None, Some(path)) => {
                let k = Intrinsics::load_json(&path).map_err(error)?;
                CameraChoice::File(path, k)
            }
            _ => {
                return Err(PyValueError::new_err(
                    "fov_deg and intrinsics cannot be given together",
                ))
            }
        };
        Ok(NativeReconstructor {
            camera,
            latency,
            models,
            inner: Mutex::new(None),
            frames: 0,
            mesh: None,
        })
    }

    /// Processes one `(H, W, 3)` uint8 RGB frame at once (latency 0); returns a dict of the
    /// results.
    #[pyo3(signature = (frame, timestamp_s=None))]
    fn process<'py>(
        &mut self,
        py: Python<'py>,
        frame: PyReadonlyArray3<'py, u8>,
        timestamp_s: Option<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        if self.latency > 0 {
            return Err(PyValueError::new_err(format!(
                "process gives each frame's result at once (latency 0); with latency={} use \
                 push(frame) and, after the last frame, end()",
                self.latency
            )));
        }
        let frame = self.frame(&frame, timestamp_s)?;
        let mut done = self.with_frame(py, Some(frame), |r, frame, mesh_wanted| {
            let frame = frame.expect("given");
            let mut p = Processed::of(r.process(&frame)?, mesh_wanted);
            p.identity = r.identity().map(|i| i.coefficients);
            Ok(vec![p])
        })?;
        Ok(done.remove(0))
    }

    /// Tracks one frame with the smoother's latency; returns the dicts of the frames it
    /// completed, in input order (none, one, or several at a cut).
    #[pyo3(signature = (frame, timestamp_s=None))]
    fn push<'py>(
        &mut self,
        py: Python<'py>,
        frame: PyReadonlyArray3<'py, u8>,
        timestamp_s: Option<f64>,
    ) -> PyResult<Bound<'py, PyList>> {
        let frame = self.frame(&frame, timestamp_s)?;
        let done = self.with_frame(py, Some(frame), |r, frame, mesh_wanted| {
            r.push(&frame.expect("given"))?;
            drain(r, mesh_wanted)
        })?;
        PyList::new(py, done)
    }

    /// The input has ended: the dicts of the frames the smoother still held back.
    fn end<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let done = self.with_frame(py, None, |r, _, mesh_wanted| {
            r.push_end()?;
            drain(r, mesh_wanted)
        })?;
        PyList::new(py, done)
    }

    /// The mesh's triangles `(F, 3)` int32, once a frame had a mesh (else `None`).
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<i32>>>> {
        let Some((t, _)) = &self.mesh else {
            return Ok(None);
        };
        let flat: Vec<i32> = t.iter().flatten().map(|&i| i as i32).collect();
        Ok(Some(PyArray1::from_vec(py, flat).reshape([t.len(), 3])?))
    }

    /// The mesh's texture coordinates `(V, 2)` float32, once a frame had a mesh (else `None`).
    #[getter]
    fn uvs<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f32>>>> {
        let Some((_, uvs)) = &self.mesh else {
            return Ok(None);
        };
        let flat: Vec<f32> = uvs.iter().flatten().map(|&x| x as f32).collect();
        Ok(Some(PyArray1::from_vec(py, flat).reshape([uvs.len(), 2])?))
    }

    /// The camera's intrinsics `(fx, fy, cx, cy)` in pixels, once the first frame set its size.
    #[getter]
    fn intrinsics(&self) -> Option<(f64, f64, f64, f64)> {
        let inner = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        inner.as_ref().map(|(r, _, _)| {
            let k = r.intrinsics();
            (k.fx, k.fy, k.cx, k.cy)
        })
    }
}
