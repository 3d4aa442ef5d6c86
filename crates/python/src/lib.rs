//! `visage._visage`, the native module of the Python package (`python/visage`): the per-frame
//! reconstructor over numpy frames, frames read from files, and visage's errors as Python
//! exceptions. The package's Python side turns what it returns into typed results.
//!
//! Frames cross as `(H, W, 3)` uint8 RGB arrays: copied once into the frame the pipeline owns
//! (a C-contiguous array in one `memcpy`). Heavy results come back as numpy arrays; records
//! (the frame's metrics, its landmarks and pose) as the JSON visage writes into a run's folder,
//! so the Python side reads the same schema as `metrics.json` and `landmarks.json`. Frames are
//! processed with the GIL released: two reconstructors run on two threads at once.

use std::path::PathBuf;
use std::sync::Mutex;

use numpy::{
    PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use visage::{Camera, Input};
use visage_video::Frame;

create_exception!(
    _visage,
    VisageError,
    PyRuntimeError,
    "An error from visage: a file that cannot be read, a model file missing, a frame that \
     cannot be processed. The message is the command line's."
);

fn error(e: impl std::fmt::Display) -> PyErr {
    VisageError::new_err(e.to_string())
}

/// The per-frame reconstructor (see the package's `Reconstructor`).
#[pyclass(module = "visage._visage")]
struct NativeReconstructor {
    fov_deg: Option<f64>,
    models: Option<PathBuf>,
    /// Made at the first frame (its size sets the camera). In a mutex: a Python object may be
    /// used from any thread (one at a time).
    inner: Mutex<Option<(visage::Reconstructor, u32, u32)>>,
    frames: usize,
    /// The mesh's triangles, once a frame had a mesh.
    triangles: Option<Vec<[u32; 3]>>,
}

#[pymethods]
impl NativeReconstructor {
    #[new]
    #[pyo3(signature = (fov_deg=None, models=None))]
    fn new(fov_deg: Option<f64>, models: Option<PathBuf>) -> PyResult<Self> {
        if let Some(fov) = fov_deg {
            visage::check_fov(fov).map_err(|e| {
                PyValueError::new_err(e.to_string().replace("--fov-deg", "fov_deg"))
            })?;
        }
        Ok(NativeReconstructor {
            fov_deg,
            models,
            inner: Mutex::new(None),
            frames: 0,
            triangles: None,
        })
    }

    /// Processes one `(H, W, 3)` uint8 RGB frame; returns a dict of the results.
    #[pyo3(signature = (frame, timestamp_s=None))]
    fn process<'py>(
        &mut self,
        py: Python<'py>,
        frame: PyReadonlyArray3<'py, u8>,
        timestamp_s: Option<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
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
        let mut inner = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, w, h)) = &*inner {
            if (*w, *h) != (width, height) {
                return Err(PyValueError::new_err(format!(
                    "frame {}: {width}×{height}, where this reconstructor's frames are {w}×{h} \
                     (make a new Reconstructor for another video)",
                    self.frames
                )));
            }
        }
        let pixels: Vec<u8> = match frame.as_slice() {
            Ok(s) => s.to_vec(),
            Err(_) => frame.as_array().iter().copied().collect(),
        };
        let image = image::RgbImage::from_raw(width, height, pixels)
            .ok_or_else(|| PyValueError::new_err("the frame's size does not match its data"))?;
        let index = self.frames;
        let frame = Frame {
            index,
            source: format!("frame {index}"),
            timestamp_s,
            image,
        };
        if inner.is_none() {
            let mut builder =
                visage::Reconstructor::builder()
                    .latency(0)
                    .camera(match self.fov_deg {
                        Some(fov) => Camera::FovDeg(fov),
                        None => Camera::Auto,
                    });
            if let Some(dir) = &self.models {
                builder = builder.models_dir(dir);
            }
            let r = builder.build(width, height).map_err(error)?;
            *inner = Some((r, width, height));
        }
        let (reconstructor, _, _) = inner.as_mut().expect("built above");
        // The GIL is released while the frame is processed.
        let out = py.detach(|| -> Result<Processed, visage::Error> {
            let r = reconstructor.process(&frame)?;
            Ok(Processed {
                index: r.index(),
                metrics: serde_json::to_string(r.metrics).unwrap_or_default(),
                landmarks: r.landmarks.faces.first().map(|f| {
                    f.landmarks
                        .iter()
                        .flat_map(|p| [p[0] as f32, p[1] as f32])
                        .collect()
                }),
                pose: r
                    .landmarks
                    .faces
                    .first()
                    .and_then(|f| f.pose.as_ref())
                    .map(|p| (p.rotation, p.translation_m)),
                vertices: r.mesh().map(|m| {
                    m.vertices
                        .iter()
                        .flat_map(|v| v.map(|x| x as f32))
                        .collect()
                }),
                triangles: r.mesh().map(|m| m.triangles.clone()),
                weights: r.blendshapes.map(|b| b.weights.to_vec()),
                head: r.blendshapes.map(|b| b.head),
                eyes: r.blendshapes.map(|b| [b.left_eye, b.right_eye]),
            })
        });
        drop(inner);
        self.frames += 1;
        let out = out.map_err(error)?;
        if self.triangles.is_none() {
            self.triangles = out.triangles;
        }
        let d = PyDict::new(py);
        d.set_item("index", out.index)?;
        d.set_item("metrics_json", out.metrics)?;
        match out.landmarks {
            Some(l) => {
                let n = l.len() / 2;
                d.set_item("landmarks", PyArray1::from_vec(py, l).reshape([n, 2])?)?;
            }
            None => d.set_item("landmarks", py.None())?,
        }
        match out.pose {
            Some((rotation, translation)) => {
                let mut m = [0.0f64; 16];
                for r in 0..3 {
                    m[4 * r..4 * r + 3].copy_from_slice(&rotation[r]);
                    m[4 * r + 3] = translation[r];
                }
                m[15] = 1.0;
                d.set_item(
                    "head_pose",
                    PyArray1::from_vec(py, m.to_vec()).reshape([4, 4])?,
                )?;
            }
            None => d.set_item("head_pose", py.None())?,
        }
        match out.vertices {
            Some(v) => {
                let n = v.len() / 3;
                let a = PyArray1::from_vec(py, v).reshape([n, 3])?;
                d.set_item("vertices", a)?;
            }
            None => d.set_item("vertices", py.None())?,
        }
        match out.weights {
            Some(w) => d.set_item("weights", PyArray1::from_vec(py, w))?,
            None => d.set_item("weights", py.None())?,
        }
        d.set_item("head", out.head)?;
        d.set_item("eyes", out.eyes)?;
        Ok(d)
    }

    /// The mesh's triangles `(F, 3)` int32, once a frame had a mesh (else `None`).
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<i32>>>> {
        let Some(t) = &self.triangles else {
            return Ok(None);
        };
        let flat: Vec<i32> = t.iter().flatten().map(|&i| i as i32).collect();
        Ok(Some(PyArray1::from_vec(py, flat).reshape([t.len(), 3])?))
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

/// What `process` hands back across the GIL.
struct Processed {
    index: usize,
    metrics: String,
    /// The first face's 468 landmarks, `[x, y]` pixels, flat.
    landmarks: Option<Vec<f32>>,
    /// Its metric head pose: rotation and translation (metres), model → camera.
    pose: Option<([[f64; 3]; 3], [f64; 3])>,
    vertices: Option<Vec<f32>>,
    triangles: Option<Vec<[u32; 3]>>,
    weights: Option<Vec<f32>>,
    head: Option<[f32; 3]>,
    eyes: Option<[[f32; 3]; 2]>,
}

/// A frame as Python gets it: `(index, timestamp_s, (H, W, 3) uint8 RGB)`.
type NumpyFrame<'py> = (usize, Option<f64>, Bound<'py, PyArray3<u8>>);

/// Frames of a video, an image folder or an image, as `visage run` reads them.
#[pyclass(module = "visage._visage")]
struct NativeFrames {
    input: Mutex<Input>,
    size: (u32, u32),
    fps: Option<f64>,
}

#[pymethods]
impl NativeFrames {
    #[new]
    fn new(path: PathBuf) -> PyResult<Self> {
        let input = Input::open(&path).map_err(error)?;
        Ok(NativeFrames {
            size: input.size(),
            fps: input.frame_rate(),
            input: Mutex::new(input),
        })
    }

    /// `(width, height)` of the frames.
    #[getter]
    fn size(&self) -> (u32, u32) {
        self.size
    }

    /// Frames per second, when the input says.
    #[getter]
    fn fps(&self) -> Option<f64> {
        self.fps
    }

    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    /// The next `(index, timestamp_s, frame)`, the frame `(H, W, 3)` uint8 RGB.
    fn __next__<'py>(&mut self, py: Python<'py>) -> PyResult<Option<NumpyFrame<'py>>> {
        let input = &self.input;
        let next = py.detach(|| input.lock().unwrap_or_else(|e| e.into_inner()).next());
        let Some(frame) = next else {
            return Ok(None);
        };
        let frame = frame.map_err(error)?;
        let (w, h) = frame.image.dimensions();
        let array =
            PyArray1::from_vec(py, frame.image.into_raw()).reshape([h as usize, w as usize, 3])?;
        Ok(Some((frame.index, frame.timestamp_s, array)))
    }
}

#[pymodule]
fn _visage(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<NativeReconstructor>()?;
    m.add_class::<NativeFrames>()?;
    m.add("VisageError", m.py().get_type::<VisageError>())?;
    m.add("ARKIT_BLENDSHAPES", visage::ARKIT_BLENDSHAPES.to_vec())?;
    Ok(())
}
