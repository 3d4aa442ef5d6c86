//! `visage._visage`, the native module of the Python package (`python/visage`): the per-frame
//! reconstructor over numpy frames (`reconstructor.rs`), a clip run into a folder as `visage
//! run` does it (`run.rs`), frames read from files (`frames.rs`), and visage's errors as Python
//! exceptions (`error.rs`). The package's Python side turns what it returns into typed results.
//!
//! Heavy results cross as numpy arrays; records (a frame's metrics, a run's summary) as the
//! JSON visage writes into a run's folder, so the Python side reads the same schema as
//! `metrics.json`. The GIL is released while frames are processed.

mod error;
mod frames;
mod reconstructor;
mod run;

use pyo3::prelude::*;

#[pymodule]
fn _visage(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<reconstructor::NativeReconstructor>()?;
    m.add_class::<frames::NativeFrames>()?;
    m.add_function(wrap_pyfunction!(run::run, m)?)?;
    m.add("VisageError", m.py().get_type::<error::VisageError>())?;
    m.add("ARKIT_BLENDSHAPES", visage::ARKIT_BLENDSHAPES.to_vec())?;
    Ok(())
}
