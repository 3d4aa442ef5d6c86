//! The convolutions: `CONV_2D` (weights re-laid out once as `[k_h·k_w·C_in, C_out]`, output
//! channels contiguous) and `DEPTHWISE_CONV_2D` (depth multiplier 1); no dilation.

use super::limits::Budget;
use super::operands::Operands;
use crate::network::step::Step;
use crate::ops::{Conv2dWeights, Window};
use crate::NnError;

/// `CONV_2D`, with its fused activation (none or `RELU`).
pub(super) fn conv2d(o: &Operands, budget: &Budget) -> Result<Step, NnError> {
    let (op, shapes, y) = (o.op, o.shapes, o.y);
    let x = o.activation(o.input(0)?)?;
    let [h, w, ci] = o.nhwc(x)?;
    let (kt, bt) = (o.input(1)?, o.input(2)?);
    let (kernel, bias) = (o.constant(kt)?, o.constant(bt)?);
    let &[co, kh, kw, kci] = shapes[kt].as_slice() else {
        return Err(o.error(format!("kernel shape {:?}", shapes[kt])));
    };
    if kci != ci || bias.len() != co || op.options.dilation != [1, 1] {
        return Err(o.error(format!(
            "kernel {:?} does not fit input {:?}",
            shapes[kt], shapes[x]
        )));
    }
    let win = Window::new(h, w, [kh, kw], op.options.stride, op.options.padding);
    o.check_output([win.out_h, win.out_w, co])?;
    budget.charge(kernel.len() + bias.len())?;
    let wts = Conv2dWeights::from_ohwi(kernel, co, kh, kw, ci, bias.clone());
    Ok(Step::Conv {
        x,
        y,
        win,
        wts,
        act: o.act,
    })
}

/// `DEPTHWISE_CONV_2D` with depth multiplier 1 and no fused activation.
pub(super) fn depthwise_conv2d(o: &Operands, budget: &Budget) -> Result<Step, NnError> {
    let (op, shapes, y) = (o.op, o.shapes, o.y);
    let x = o.activation(o.input(0)?)?;
    let [h, w, c] = o.nhwc(x)?;
    let (kt, bt) = (o.input(1)?, o.input(2)?);
    let (kernel, bias) = (o.constant(kt)?, o.constant(bt)?);
    let &[1, kh, kw, kc] = shapes[kt].as_slice() else {
        return Err(o.error(format!("kernel shape {:?}", shapes[kt])));
    };
    if kc != c
        || bias.len() != c
        || op.options.depth_multiplier != 1
        || op.options.dilation != [1, 1]
    {
        return Err(o.error(format!(
            "kernel {:?} does not fit input {:?}",
            shapes[kt], shapes[x]
        )));
    }
    let win = Window::new(h, w, [kh, kw], op.options.stride, op.options.padding);
    o.check_output([win.out_h, win.out_w, c])?;
    budget.charge(kernel.len() + bias.len())?;
    Ok(Step::Depthwise {
        x,
        y,
        win,
        c,
        w: kernel.clone(),
        b: bias.clone(),
    })
}
