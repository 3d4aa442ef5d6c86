//! A small CPU inference engine for TFLite convolutional networks, in pure Rust: it runs
//! MediaPipe's face detectors (BlazeFace short range, full range), FaceMesh landmark networks
//! (with and without attention) and iris network (used by `visage-face`) from the original
//! `.tflite` files, without TensorFlow, tract or a C library.
//!
//! # What it runs
//! One subgraph with one float32 input, batch 1, NHWC image tensors (and, between MediaPipe's
//! custom operators, landmarks `[1, N, D]` and 4×4 matrices `[1, 4, 4]`), any number of
//! outputs; activations are float32, constant tensors float32, float16 (dense, or sparse behind
//! `DENSIFY`) or int32 (pad amounts, sizes, slice bounds). The operators are those of
//! MediaPipe's face networks:
//!
//! | TFLite operator | kernel |
//! |---|---|
//! | `CONV_2D` | [`ops::conv2d`]: 1×1 stride-1 as a register-blocked GEMM (4 pixels × 16/8/4 output channels; with AVX2+FMA 6 pixels × 16 channels in explicit vector code), other sizes read in place where the window is inside the input and through a small im2col at the border (with AVX2+FMA and 32 output channels or more, every pixel's window gathered, 6 pixels at a time, for the same 6 × 16 kernel); with AVX-512 every pixel through one 12-pixel × 32-channel block over weights packed in 32-channel panels; fused `RELU` applied to the register block before the store |
//! | `DEPTHWISE_CONV_2D` | [`ops::depthwise_conv2d`] (depth multiplier 1; 3×3 interior rows with the nine weight vectors in registers; with AVX2+FMA six columns × eight channels in explicit vector code; with AVX-512 eight columns × 16 channels, and the border pixels in 16-channel vectors) |
//! | `MAX_POOL_2D` | [`ops::max_pool2d`] (like `ADD` and `PRELU`, compiled apart for AVX2: [`ops::separately`]) |
//! | `PAD` | [`ops::pad4`] (constant int32 paddings) |
//! | `ADD` | [`ops::add`] (same shapes, no broadcasting; optional fused `RELU`) |
//! | `MUL` | [`ops::mul`] (same shapes, or by a constant of one value; no fused activation) |
//! | `PRELU` / `RELU` | [`ops::prelu`] (one slope per channel) / [`ops::relu`]; an `ADD` whose sum only the next `PRELU` reads runs as one pass ([`ops::add_prelu`]) |
//! | `RESIZE_BILINEAR` | [`ops::resize_bilinear`] (constant size; `half_pixel_centers` or `align_corners`, TensorFlow's sampling) |
//! | `DEPTH_TO_SPACE` | [`ops::depth_to_space`] (TensorFlow's DCR order) |
//! | `RESHAPE`, `CONCATENATION` | copies |
//! | `STRIDED_SLICE` | [`ops::strided_slice`] (rank ≤ 4, constant bounds and strides, negative ones too; begin, end and shrink masks, `offset`; no ellipsis or new axis) |
//! | `Landmarks2TransformMatrix` (custom, v2) | [`ops::landmarks_to_transform_matrix`]: landmarks `[1, N, 3]` → the 4×4 matrix of a rotated crop around some of them |
//! | `TransformTensorBilinear` (custom, v2) | [`ops::transform_tensor_bilinear`]: a bilinear crop of an NHWC tensor through that matrix (pixel centres, zeros outside) |
//! | `TransformLandmarks` (custom, v2) | [`ops::transform_landmarks`]: points `[1, N, 2 or 3]` mapped by the matrix |
//! | `DEQUANTIZE`, `DENSIFY` | folded at load time (below) |
//!
//! Convolutions and pooling follow TensorFlow's `SAME`/`VALID` padding ([`ops::Window`]); fused
//! activations other than `RELU` on `CONV_2D` and `ADD`, dilation, broadcasting adds and the
//! other broadcasts of `MUL` are rejected when the graph is compiled, with a [`NnError`] naming
//! the operator. The custom operators are MediaPipe's (its `util/tflite/operations`), read by
//! their `custom_code` and version (version 1 of each is rejected); their options are
//! FlexBuffer maps, read by a small bounds-checked reader of our own and checked key by key.
//!
//! # Pipeline
//! - [`tflite`] reads the flatbuffer by hand, bounds-checked: a corrupt or truncated file is an
//!   error, never a panic; so does `flexbuffer` the custom operators' options
//!   (`custom_options`: [`tflite::CustomOptions`]).
//! - [`Network::compile`] expands sparse constants ([`sparse`], TFLite's CSR format, the
//!   full-range detector's kernels) and folds float16 constants behind `DEQUANTIZE` to f32 once
//!   ([`float16`], exact conversion), re-lays out convolution weights as
//!   `[k_h·k_w·C_in, C_out]` (output channels contiguous) and shares activation buffers between
//!   tensors whose lifetimes do not overlap, so the working set stays in cache.
//! - [`Network::run`] executes the compiled steps over those buffers and never allocates.
//!
//! # Instruction sets
//! The kernels are generic over the multiply-add ([`ops::Madd`]). On x86-64 CPUs with AVX2 and
//! FMA, [`Network::run`] calls a copy of the step loop compiled with those target features and
//! fused multiply-adds ([`ops::Fused`]), chosen at run time; elsewhere the portable path
//! ([`ops::Plain`]) runs. The two agree to float rounding. The explicit AVX2 kernels run only
//! with fused multiply-adds and keep the generic kernels' order of operations, so they give the
//! generic fused path's values.
//!
//! # Benches
//! `cargo bench -p visage-nn` times single convolution layers on random data (fixed seed), through
//! [`Network::run`]; no model file is needed.
//!
//! # Example
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let bytes = std::fs::read("models/face_landmark.tflite")?;
//! let mut net = visage_nn::Network::from_tflite(&bytes, "face_landmark.tflite")?;
//! assert_eq!(net.input_shape(), [1, 192, 192, 3]);
//! net.input_mut().fill(0.5); // NHWC, f32
//! net.run();
//! let landmarks = net.output_named("conv2d_21").expect("output");
//! # let _ = landmarks;
//! # Ok(())
//! # }
//! ```

// Unsafe code is denied except in `network::run`, whose one block calls the AVX2 + FMA build of
// the kernels after the run-time CPU check, in `ops::separately` (the same for the memory-bound
// passes) and in the explicit vector kernels (`ops::avx512`, the `avx2` modules of the
// convolutions and of `bilinear`), each block with its `SAFETY:`.
#![deny(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn, clippy::undocumented_unsafe_blocks)]

pub mod bilinear;
mod custom_options;
mod error;
mod flexbuffer;
pub mod float16;
pub mod network;
pub mod ops;
pub mod sparse;
pub mod tflite;

pub use error::NnError;
pub use network::{Network, StepProfile};
pub use tflite::TfliteModel;
