//! Compiling a TFLite model into a [`Network`]: the passes in order, each in its own file.
//!
//! 1. `limits`: every tensor's size within [`MAX_TENSOR_VALUES`], before anything is
//!    allocated; the values allocated from then on counted against [`MAX_NETWORK_VALUES`].
//! 2. `constants`: the constant tensors read (sparse ones expanded, float16 ones folded to f32).
//! 3. Each operator, its operands resolved and checked (`operands`), compiled by its family:
//!    `fold` (`DEQUANTIZE`, `DENSIFY`: a constant, no step), `convolution`, `elementwise`,
//!    `spatial` (resize, depth-to-space, pooling, padding), `copies` (reshape, concatenation,
//!    strided slice) and `landmarks` (MediaPipe's custom operators of the attention face mesh).
//! 4. `fuse`: an `ADD` merged into the `PRELU` that alone reads it.
//! 5. The activation buffers planned ([`super::liveness`]) and allocated.

mod constants;
mod convolution;
mod copies;
mod elementwise;
mod fold;
mod fuse;
mod landmarks;
mod limits;
mod operands;
mod spatial;

pub use limits::{MAX_NETWORK_VALUES, MAX_TENSOR_VALUES};

use self::constants::Constants;
use self::fuse::fuse_add_prelu;
use self::limits::{check_tensor_sizes, Budget};
use self::operands::Operands;
use super::liveness::allocate_slots;
use super::run::Network;
use super::step::Step;
use crate::error::err;
use crate::tflite::{OpCode, TfliteModel};
use crate::NnError;

impl Network {
    /// Compiles a parsed model. `name` is used in error messages.
    ///
    /// Errors when the graph uses an operator variant the kernels do not implement (fused
    /// activations, dilation, depth multiplier ≠ 1, broadcasting adds, broadcasts of `MUL`
    /// other than by one value, non-constant weights, slices with an ellipsis or a new axis).
    pub fn compile(model: &TfliteModel, name: &str) -> Result<Network, NnError> {
        let n = model.tensors.len();
        check_tensor_sizes(model, name)?;
        let budget = Budget::new(name);
        let shapes: Vec<Vec<usize>> = model.tensors.iter().map(|t| t.shape.clone()).collect();
        let mut constants = Constants::read(model, name, &budget)?;
        let input = graph_input(model, name)?;
        let mut steps = Vec::new();
        let mut produced = vec![false; n];
        produced[input] = true;
        for (k, op) in model.operators.iter().enumerate() {
            let operands = Operands::new(model, name, k, op, &shapes, &constants, &produced)?;
            let y = operands.y;
            match compile_operator(&operands, &budget)? {
                Compiled::Constant(values) => constants.floats[y] = Some(values),
                Compiled::Step(step) => {
                    produced[y] = true;
                    steps.push(step);
                }
            }
        }
        for &o in &model.outputs {
            if !produced[o] {
                return Err(err(
                    name,
                    format!("output {} is never computed", model.tensors[o].name),
                ));
            }
        }
        let steps = fuse_add_prelu(steps, &model.outputs);
        let len_of: Vec<usize> = shapes.iter().map(|s| s.iter().product()).collect();
        let (slot_of, slot_len) = allocate_slots(&steps, &len_of, input, &model.outputs);
        let scratch_len = steps
            .iter()
            .map(|s| match s {
                Step::Conv { win, wts, .. } => {
                    crate::ops::conv2d_scratch_len(win.k_h, win.k_w, wts.c_in)
                }
                _ => 0,
            })
            .max()
            .unwrap_or(0);
        let buffers = slot_len
            .iter()
            .fold(scratch_len, |a, &l| a.saturating_add(l));
        budget.charge(buffers)?;
        let values = slot_len.iter().map(|&l| vec![0.0; l]).collect();
        Ok(Network {
            steps,
            values,
            slot_of,
            len_of,
            shapes,
            names: model.tensors.iter().map(|t| t.name.clone()).collect(),
            input,
            outputs: model.outputs.clone(),
            scratch: vec![0.0; scratch_len],
        })
    }

    /// Parses and compiles a `.tflite` file's bytes.
    pub fn from_tflite(bytes: &[u8], name: &str) -> Result<Network, NnError> {
        Network::compile(&TfliteModel::parse(bytes, name)?, name)
    }
}

/// The graph's one input tensor.
fn graph_input(model: &TfliteModel, name: &str) -> Result<usize, NnError> {
    let Some(&input) = model.inputs.first() else {
        return Err(err(name, "no graph input".into()));
    };
    // Only the first input gets a buffer ([`Network::input_mut`]); another one, read by an
    // operator or listed as an output, would have none.
    if model.inputs.len() > 1 {
        return Err(err(
            name,
            format!(
                "the graph has {} inputs; this engine runs graphs of one",
                model.inputs.len()
            ),
        ));
    }
    Ok(input)
}

/// What one operator compiles to.
enum Compiled {
    /// The value of a constant output (an operator folded at load time).
    Constant(Vec<f32>),
    /// A kernel call.
    Step(Step),
}

/// Compiles one operator by its family.
fn compile_operator(o: &Operands, budget: &Budget) -> Result<Compiled, NnError> {
    let step = match o.op.code {
        OpCode::Dequantize => return fold::dequantize(o, budget).map(Compiled::Constant),
        OpCode::Densify => return fold::densify(o, budget).map(Compiled::Constant),
        OpCode::Conv2d => convolution::conv2d(o, budget)?,
        OpCode::DepthwiseConv2d => convolution::depthwise_conv2d(o, budget)?,
        OpCode::Prelu => elementwise::prelu(o, budget)?,
        OpCode::Relu => elementwise::relu(o)?,
        OpCode::Add => elementwise::add(o)?,
        OpCode::ResizeBilinear => spatial::resize_bilinear(o, budget)?,
        OpCode::DepthToSpace => spatial::depth_to_space(o)?,
        OpCode::MaxPool2d => spatial::max_pool2d(o)?,
        OpCode::Pad => spatial::pad(o)?,
        OpCode::Reshape => copies::reshape(o)?,
        OpCode::Concatenation => copies::concatenation(o)?,
        OpCode::Mul => elementwise::mul(o, budget)?,
        OpCode::StridedSlice => copies::strided_slice(o)?,
        OpCode::Landmarks2TransformMatrix => landmarks::landmarks_to_transform_matrix(o)?,
        OpCode::TransformTensorBilinear => landmarks::transform_tensor_bilinear(o)?,
        OpCode::TransformLandmarks => landmarks::transform_landmarks(o)?,
    };
    Ok(Compiled::Step(step))
}
