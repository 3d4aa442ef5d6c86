//! The operators folded at load time: `DEQUANTIZE` and `DENSIFY` only pass constants on
//! (already converted and expanded when they were read, [`super::constants`]), so they compile
//! to a constant, not to a step.

use super::limits::Budget;
use super::operands::Operands;
use crate::NnError;

/// `DEQUANTIZE`: the output takes its (float16, folded) input's values.
pub(super) fn dequantize(o: &Operands, budget: &Budget) -> Result<Vec<f32>, NnError> {
    let x = o.input(0)?;
    let values = o.constant(x)?;
    budget.charge(values.len())?;
    Ok(values.clone())
}

/// `DENSIFY`: the output takes its sparse input's values, expanded when the constants were
/// read.
pub(super) fn densify(o: &Operands, budget: &Budget) -> Result<Vec<f32>, NnError> {
    let x = o.input(0)?;
    if o.model.tensors[x].sparsity.is_none() || o.shapes[x] != o.shapes[o.y] {
        return Err(o.error(format!(
            "input {} must be a sparse constant of the output's shape",
            o.model.tensors[x].name
        )));
    }
    let values = o.constant(x)?;
    budget.charge(values.len())?;
    Ok(values.clone())
}
