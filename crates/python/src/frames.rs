//! Frames of a video, an image folder or an image, read as `visage run` reads them, as numpy
//! arrays (the package's `visage.open`).

use std::path::PathBuf;
use std::sync::Mutex;

use numpy::{PyArray1, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use visage::Input;

use crate::error::error;

/// A frame as Python gets it: `(index, timestamp_s, (H, W, 3) uint8 RGB)`.
type NumpyFrame<'py> = (usize, Option<f64>, Bound<'py, PyArray3<u8>>);

/// Frames of a video, an image folder or an image, as `visage run` reads them.
#[pyclass(module = "visage._visage")]
pub struct NativeFrames {
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
