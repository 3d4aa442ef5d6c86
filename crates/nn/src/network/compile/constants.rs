//! Constant tensors, read once from the model's buffers: float32 and int32 as they are, float16
//! converted to f32 exactly, sparse ones expanded.

use super::limits::Budget;
use crate::error::err;
use crate::float16::f16_slice_to_f32;
use crate::sparse;
use crate::tflite::{TensorType, TfliteModel};
use crate::NnError;

/// The values of every constant tensor, by tensor index (`None` for computed tensors).
pub(super) struct Constants {
    /// Floating-point constants: float32 buffers directly, float16 through `DEQUANTIZE`.
    pub(super) floats: Vec<Option<Vec<f32>>>,
    /// Int32 constants (pad amounts, sizes).
    pub(super) ints: Vec<Option<Vec<i32>>>,
}

impl Constants {
    /// Reads every tensor that has a buffer, counting its values against `budget`. Errors on
    /// an unsupported type, a buffer whose size does not fit the shape, and a sparse tensor
    /// that is not floating-point or whose indices do not fit.
    pub(super) fn read(
        model: &TfliteModel,
        name: &str,
        budget: &Budget,
    ) -> Result<Constants, NnError> {
        let n = model.tensors.len();
        let mut consts: Vec<Option<Vec<f32>>> = vec![None; n];
        let mut ints: Vec<Option<Vec<i32>>> = vec![None; n];
        for (i, t) in model.tensors.iter().enumerate() {
            let data = &model.buffers[t.buffer];
            if data.is_empty() {
                continue;
            }
            let dense_count: usize = t.shape.iter().product();
            let width = match t.dtype {
                TensorType::Float32 | TensorType::Int32 => 4,
                TensorType::Float16 => 2,
                TensorType::Other(code) => {
                    return Err(err(
                        name,
                        format!("tensor {} has unsupported type {code}", t.name),
                    ))
                }
            };
            // A sparse constant stores only its non-zeros; it is expanded below.
            let count_ok = match t.sparsity {
                Some(_) => data.len().is_multiple_of(width),
                None => Some(data.len()) == dense_count.checked_mul(width),
            };
            if !count_ok {
                return Err(err(
                    name,
                    format!(
                        "tensor {} has {} bytes for shape {:?}",
                        t.name,
                        data.len(),
                        t.shape
                    ),
                ));
            }
            budget.charge(data.len() / width)?;
            match t.dtype {
                TensorType::Float32 => {
                    consts[i] = Some(
                        data.chunks_exact(4)
                            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                            .collect(),
                    )
                }
                TensorType::Float16 => consts[i] = Some(f16_slice_to_f32(data)),
                TensorType::Int32 => {
                    ints[i] = Some(
                        data.chunks_exact(4)
                            .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                            .collect(),
                    )
                }
                TensorType::Other(_) => {}
            }
            if let Some(sparsity) = &t.sparsity {
                let values = consts[i].take().ok_or_else(|| {
                    err(
                        name,
                        format!("sparse tensor {} is not floating-point", t.name),
                    )
                })?;
                budget.charge(dense_count)?;
                let dense = sparse::densify(sparsity, &t.shape, &values)
                    .map_err(|e| err(name, format!("sparse tensor {}: {e}", t.name)))?;
                consts[i] = Some(dense);
            }
        }
        Ok(Constants {
            floats: consts,
            ints,
        })
    }
}
