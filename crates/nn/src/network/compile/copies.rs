//! The operators that only copy values: `RESHAPE` (same number of values) and
//! `CONCATENATION` (along any axis).

use super::operands::Operands;
use crate::network::step::Step;
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
