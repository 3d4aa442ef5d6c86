//! The graph compiler and runner: a TFLite graph is compiled once into a list of kernel calls
//! over pre-allocated buffers, then run per input without allocating.
//!
//! Why not tract: `tract-tflite` 0.23 refuses MediaPipe's face networks (no `DEQUANTIZE`, no
//! `PRELU`, registry not extensible, no MediaPipe custom operators). Those networks use fifteen
//! built-in operators, all NHWC with batch 1, and the attention face mesh three custom ones, so
//! the engine expands the sparse `DENSIFY` constants and folds the float16 `DEQUANTIZE`
//! constants to f32 at load time, re-lays out convolution weights for channel-contiguous inner
//! loops and runs the hand-written kernels of [`crate::ops`].
//!
//! # Files
//! - `step`: the compiled plan's instruction (`Step`), one kernel call over
//!   tensor indices, and the tensors each one reads and writes.
//! - `compile/`: [`Network::compile`], from a parsed model to the step list: the limits that
//!   keep a corrupt model from allocating without bound ([`MAX_TENSOR_VALUES`],
//!   [`MAX_NETWORK_VALUES`]), the constants, one file per operator family, the fusion pass.
//! - `liveness`: buffer planning, the activation buffer ("slot") of each tensor from the
//!   tensors' lifetimes.
//! - `run`: the [`Network`] type, its input and outputs, and [`Network::run`].
//! - `profile`: [`Network::profile`] and its [`StepProfile`].
//! - `dims`: shapes in words, for error messages and profiles.

mod compile;
mod dims;
mod liveness;
mod profile;
// The one unsafe block calls the AVX2 + FMA build of the step loop after the run-time CPU check.
#[allow(unsafe_code)]
mod run;
mod step;
#[cfg(test)]
mod tests;

pub use compile::{MAX_NETWORK_VALUES, MAX_TENSOR_VALUES};
pub use profile::StepProfile;
pub use run::Network;
