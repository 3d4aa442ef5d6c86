//! One operator's operands, resolved and checked for the operator-family compilers: its fused
//! activation, its output, which tensor each input is, constant values, computed tensors that
//! must already be computed, NHWC shapes; errors name the model, the operator and its code.

use super::constants::Constants;
use crate::error::err;
use crate::network::dims::dims;
use crate::ops::Activation;
use crate::tflite::{OpCode, Operator, TfliteModel};
use crate::NnError;

/// Operator `k` of the model with the tensors known so far.
pub(super) struct Operands<'a> {
    pub(super) model: &'a TfliteModel,
    pub(super) op: &'a Operator,
    k: usize,
    name: &'a str,
    /// Shape of each tensor.
    pub(super) shapes: &'a [Vec<usize>],
    constants: &'a Constants,
    /// Whether each tensor is computed by an earlier step (or is the graph input).
    produced: &'a [bool],
    /// The fused activation: `RELU` on `CONV_2D` and `ADD` (their kernels apply it), none
    /// elsewhere.
    pub(super) act: Activation,
    /// The output tensor.
    pub(super) y: usize,
}

impl<'a> Operands<'a> {
    /// Operator `k`, `op`, of `model` (called `name` in errors). Errors on a fused activation
    /// the kernels do not apply, and on an operator without output.
    pub(super) fn new(
        model: &'a TfliteModel,
        name: &'a str,
        k: usize,
        op: &'a Operator,
        shapes: &'a [Vec<usize>],
        constants: &'a Constants,
        produced: &'a [bool],
    ) -> Result<Operands<'a>, NnError> {
        let mut o = Operands {
            model,
            op,
            k,
            name,
            shapes,
            constants,
            produced,
            act: Activation::None,
            y: 0,
        };
        o.act = match (op.options.activation, op.code) {
            (0, _) => Activation::None,
            (1, OpCode::Conv2d | OpCode::Add) => Activation::Relu,
            (a, _) => {
                return Err(o.error(format!("fused activation {a} not supported")));
            }
        };
        let Some(&y) = op.outputs.first() else {
            return Err(o.error("no output".into()));
        };
        o.y = y;
        Ok(o)
    }

    /// An error about this operator.
    pub(super) fn error(&self, reason: String) -> NnError {
        err(
            self.name,
            format!("operator {} ({:?}): {reason}", self.k, self.op.code),
        )
    }

    /// The tensor of input `j`.
    pub(super) fn input(&self, j: usize) -> Result<usize, NnError> {
        self.op
            .inputs
            .get(j)
            .and_then(|&t| usize::try_from(t).ok())
            .ok_or_else(|| self.error(format!("missing input {j}")))
    }

    /// The values of tensor `t`, which must be a floating-point constant with the values its
    /// shape says.
    pub(super) fn constant(&self, t: usize) -> Result<&'a Vec<f32>, NnError> {
        let values = self.constants.floats[t].as_ref().ok_or_else(|| {
            self.error(format!(
                "tensor {} must be a constant",
                self.model.tensors[t].name
            ))
        })?;
        // A DEQUANTIZE output takes its input's values, whatever its own shape says.
        let len: usize = self.shapes[t].iter().product();
        if values.len() != len {
            return Err(self.error(format!(
                "constant {} has {} values for its shape {}",
                self.model.tensors[t].name,
                values.len(),
                dims(&self.shapes[t])
            )));
        }
        Ok(values)
    }

    /// Whether tensor `t` is a floating-point constant.
    pub(super) fn is_constant(&self, t: usize) -> bool {
        self.constants.floats[t].is_some()
    }

    /// The values of tensor `t` if it is an int32 constant.
    pub(super) fn int_constant(&self, t: usize) -> Option<&'a Vec<i32>> {
        self.constants.ints[t].as_ref()
    }

    /// Tensor `t`, which an earlier step must have computed (or the graph input).
    pub(super) fn activation(&self, t: usize) -> Result<usize, NnError> {
        if self.produced[t] {
            Ok(t)
        } else {
            Err(self.error(format!(
                "tensor {} is used before it is computed",
                self.model.tensors[t].name
            )))
        }
    }

    /// `[H, W, C]` of tensor `t`, which must have shape `[1, H, W, C]`.
    pub(super) fn nhwc(&self, t: usize) -> Result<[usize; 3], NnError> {
        match self.shapes[t].as_slice() {
            &[1, h, w, c] => Ok([h, w, c]),
            s => Err(self.error(format!(
                "tensor {} has shape {s:?}, expected [1, H, W, C]",
                self.model.tensors[t].name
            ))),
        }
    }

    /// Checks that the output has shape `[1, H, W, C]` with `hwc` = `[H, W, C]`.
    pub(super) fn check_output(&self, hwc: [usize; 3]) -> Result<(), NnError> {
        let shape: &[usize] = &self.shapes[self.y];
        if shape == [1, hwc[0], hwc[1], hwc[2]] {
            Ok(())
        } else {
            Err(self.error(format!(
                "output shape {shape:?}, computed [1, {}, {}, {}]",
                hwc[0], hwc[1], hwc[2]
            )))
        }
    }
}
