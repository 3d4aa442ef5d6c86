//! The element-wise operators: `PRELU` (one slope per channel), `RELU`, `ADD` (same shapes,
//! no broadcasting; fused `RELU` or none) and `MUL` (same shapes, or by a one-value constant).

use super::limits::Budget;
use super::operands::Operands;
use crate::network::step::Step;
use crate::NnError;

/// `PRELU` with one slope per channel (the last dimension).
pub(super) fn prelu(o: &Operands, budget: &Budget) -> Result<Step, NnError> {
    let (shapes, y) = (o.shapes, o.y);
    let x = o.activation(o.input(0)?)?;
    let alpha = o.constant(o.input(1)?)?;
    budget.charge(alpha.len())?;
    let alpha = alpha.clone();
    let c = *shapes[x].last().unwrap_or(&0);
    if alpha.len() != c || shapes[y] != shapes[x] {
        return Err(o.error(format!("alpha of {} values for {c} channels", alpha.len())));
    }
    Ok(Step::Prelu { x, y, alpha })
}

/// `RELU`.
pub(super) fn relu(o: &Operands) -> Result<Step, NnError> {
    let x = o.activation(o.input(0)?)?;
    Ok(Step::Relu { x, y: o.y })
}

/// `ADD` of two tensors of the output's shape, with its fused activation (none or `RELU`).
pub(super) fn add(o: &Operands) -> Result<Step, NnError> {
    let (shapes, y) = (o.shapes, o.y);
    let (a, b) = (o.activation(o.input(0)?)?, o.activation(o.input(1)?)?);
    if shapes[a] != shapes[b] || shapes[a] != shapes[y] {
        return Err(o.error(format!(
            "broadcasting add {:?} + {:?} not supported",
            shapes[a], shapes[b]
        )));
    }
    Ok(Step::Add {
        a,
        b,
        y,
        act: o.act,
    })
}

/// `MUL` (no fused activation) of a computed tensor by a computed tensor or a constant of its
/// shape, or by a constant of one value; the operands in either order. Other broadcasts are
/// rejected.
pub(super) fn mul(o: &Operands, budget: &Budget) -> Result<Step, NnError> {
    let (shapes, y) = (o.shapes, o.y);
    let (ta, tb) = (o.input(0)?, o.input(1)?);
    let (x, other) = match (o.is_constant(ta), o.is_constant(tb)) {
        (true, true) => return Err(o.error("both operands are constants".into())),
        (true, false) => (tb, ta),
        _ => (ta, tb),
    };
    let x = o.activation(x)?;
    let broadcast = || {
        o.error(format!(
            "broadcasting mul {:?} × {:?} not supported",
            shapes[x], shapes[other]
        ))
    };
    if shapes[y] != shapes[x] {
        return Err(broadcast());
    }
    if o.is_constant(other) {
        let c = o.constant(other)?;
        if c.len() != 1 && shapes[other] != shapes[x] {
            return Err(broadcast());
        }
        budget.charge(c.len())?;
        return Ok(Step::MulConstant { x, y, c: c.clone() });
    }
    let b = o.activation(other)?;
    if shapes[b] != shapes[x] {
        return Err(broadcast());
    }
    Ok(Step::Mul { a: x, b, y })
}
