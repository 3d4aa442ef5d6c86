//! The operators that only copy values: `RESHAPE` (same number of values),
//! `CONCATENATION` (along any axis) and `STRIDED_SLICE` (constant begin, end and strides).

use super::operands::Operands;
use crate::network::step::Step;
use crate::ops::StridedSlice;
use crate::NnError;

/// `RESHAPE`: a copy into the output's shape, which must hold as many values.
pub(super) fn reshape(o: &Operands) -> Result<Step, NnError> {
    let (shapes, y) = (o.shapes, o.y);
    let x = o.activation(o.input(0)?)?;
    if shapes[x].iter().product::<usize>() != shapes[y].iter().product::<usize>() {
        return Err(o.error(format!("reshape {:?} → {:?}", shapes[x], shapes[y])));
    }
    Ok(Step::Copy { x, y })
}

/// `CONCATENATION` of all the inputs along the operator's axis (negative: from the end).
pub(super) fn concatenation(o: &Operands) -> Result<Step, NnError> {
    let (op, shapes, y) = (o.op, o.shapes, o.y);
    let xs = op
        .inputs
        .iter()
        .map(|&t| {
            usize::try_from(t)
                .map_err(|_| o.error("absent input".into()))
                .and_then(|t| o.activation(t))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let rank = shapes[y].len() as i32;
    let axis = if op.options.axis < 0 {
        op.options.axis + rank
    } else {
        op.options.axis
    };
    if !(0..rank).contains(&axis) {
        return Err(o.error(format!("axis {} for rank {rank}", op.options.axis)));
    }
    let outer: usize = shapes[y][..axis as usize].iter().product();
    let total: usize = xs
        .iter()
        .map(|&t| shapes[t].iter().product::<usize>())
        .sum();
    if total != shapes[y].iter().product::<usize>() {
        return Err(o.error("concatenated sizes do not add up".into()));
    }
    Ok(Step::Concat { xs, y, outer })
}

/// `STRIDED_SLICE` of a computed tensor of rank ≤ 4 by constant int32 `begin`, `end` and
/// `strides` with the operator's masks (no ellipsis, no new axis: [`StridedSlice::new`]); the
/// output's shape must be the slice's.
pub(super) fn strided_slice(o: &Operands) -> Result<Step, NnError> {
    let (shapes, y) = (o.shapes, o.y);
    let x = o.activation(o.input(0)?)?;
    let ints = |j: usize, what: &str| -> Result<&Vec<i32>, NnError> {
        o.int_constant(o.input(j)?)
            .ok_or_else(|| o.error(format!("{what} must be a constant int32 tensor")))
    };
    let (begin, end, strides) = (ints(1, "begin")?, ints(2, "end")?, ints(3, "strides")?);
    let (slice, out) = StridedSlice::new(&shapes[x], begin, end, strides, o.op.options.slice)
        .map_err(|r| o.error(r))?;
    if out != shapes[y] {
        return Err(o.error(format!("slice of shape {out:?}, output {:?}", shapes[y])));
    }
    Ok(Step::StridedSlice { x, y, slice })
}
