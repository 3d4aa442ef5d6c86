//! visage's errors as a Python exception, `VisageError`, carrying the command line's message.

use pyo3::create_exception;
use pyo3::exceptions::PyRuntimeError;
use pyo3::PyErr;

create_exception!(
    _visage,
    VisageError,
    PyRuntimeError,
    "An error from visage: a file that cannot be read, a model file missing, a frame that \
     cannot be processed. The message is the command line's."
);

/// `e` as a [`VisageError`] with its message.
pub fn error(e: impl std::fmt::Display) -> PyErr {
    VisageError::new_err(e.to_string())
}
