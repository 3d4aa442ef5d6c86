//! The operators that change the height and width: `RESIZE_BILINEAR` (constant size),
//! `DEPTH_TO_SPACE`, `MAX_POOL_2D` and `PAD` (constant paddings).

use super::limits::Budget;
use super::operands::Operands;
use crate::network::step::Step;
use crate::ops::{ResizeAxis, Window};
use crate::NnError;

/// `RESIZE_BILINEAR` to a constant int32 size, with `half_pixel_centers` or `align_corners`
/// (not both).
pub(super) fn resize_bilinear(o: &Operands, budget: &Budget) -> Result<Step, NnError> {
    let (op, shapes) = (o.op, o.shapes);
    let x = o.activation(o.input(0)?)?;
    let [h, w, c] = o.nhwc(x)?;
    let size = o
        .int_constant(o.input(1)?)
        .ok_or_else(|| o.error("size must be a constant int32 tensor".into()))?;
    let &[oh, ow] = size.as_slice() else {
        return Err(o.error(format!("size {size:?}")));
    };
    let (oh, ow) = (usize::try_from(oh), usize::try_from(ow));
    let (Ok(oh), Ok(ow)) = (oh, ow) else {
        return Err(o.error(format!("negative size {size:?}")));
    };
    if h == 0 || w == 0 {
        return Err(o.error(format!("empty input {:?}", shapes[x])));
    }
    o.check_output([oh, ow, c])?;
    let (ac, hp) = (op.options.align_corners, op.options.half_pixel_centers);
    if ac && hp {
        return Err(o.error("align_corners with half_pixel_centers".into()));
    }
    // Per output row and column: two indices and a weight, five f32s' worth.
    budget.charge(5 * (oh + ow))?;
    Ok(Step::Resize {
        x,
        y: o.y,
        in_w: w,
        c,
        rows: ResizeAxis::new(h, oh, ac, hp),
        cols: ResizeAxis::new(w, ow, ac, hp),
    })
}

/// `DEPTH_TO_SPACE` with a block size of at least 2 that divides the channels.
pub(super) fn depth_to_space(o: &Operands) -> Result<Step, NnError> {
    let x = o.activation(o.input(0)?)?;
    let [h, w, c] = o.nhwc(x)?;
    let block = o.op.options.block_size;
    if block < 2 || !c.is_multiple_of(block * block) {
        return Err(o.error(format!("block size {block} for {c} channels")));
    }
    let c_out = c / (block * block);
    o.check_output([h * block, w * block, c_out])?;
    Ok(Step::DepthToSpace {
        x,
        y: o.y,
        h,
        w,
        c_out,
        block,
    })
}

/// `MAX_POOL_2D`.
pub(super) fn max_pool2d(o: &Operands) -> Result<Step, NnError> {
    let op = o.op;
    let x = o.activation(o.input(0)?)?;
    let [h, w, c] = o.nhwc(x)?;
    let win = Window::new(
        h,
        w,
        op.options.filter,
        op.options.stride,
        op.options.padding,
    );
    o.check_output([win.out_h, win.out_w, c])?;
    Ok(Step::MaxPool { x, y: o.y, win, c })
}

/// `PAD` of a rank-4 tensor by constant, non-negative int32 paddings.
pub(super) fn pad(o: &Operands) -> Result<Step, NnError> {
    let (shapes, y) = (o.shapes, o.y);
    let x = o.activation(o.input(0)?)?;
    let pt = o.input(1)?;
    let p = o
        .int_constant(pt)
        .ok_or_else(|| o.error("paddings must be a constant int32 tensor".into()))?;
    let shape: [usize; 4] = match shapes[x].as_slice() {
        &[a, b, c, d] => [a, b, c, d],
        s => return Err(o.error(format!("pad of a rank-{} tensor", s.len()))),
    };
    if p.len() != 8 || p.iter().any(|&v| v < 0) {
        return Err(o.error(format!("paddings {p:?}")));
    }
    let pads: [[usize; 2]; 4] = std::array::from_fn(|d| [p[2 * d] as usize, p[2 * d + 1] as usize]);
    let out: Vec<usize> = (0..4).map(|d| shape[d] + pads[d][0] + pads[d][1]).collect();
    if out != shapes[y] {
        return Err(o.error(format!("padded shape {out:?} ≠ {:?}", shapes[y])));
    }
    Ok(Step::Pad { x, y, shape, pads })
}
