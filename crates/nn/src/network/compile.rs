//! Compiling a TFLite model into a [`Network`]: constants read (sparse ones expanded, float16
//! ones folded to f32), each operator checked and turned into a [`Step`], an `ADD` fused into
//! the `PRELU` that alone reads it, and activation buffers planned and allocated.

use super::dims::dims;
use super::liveness::allocate_slots;
use super::run::Network;
use super::step::Step;
use crate::float16::f16_slice_to_f32;
use crate::ops::{Activation, Conv2dWeights, ResizeAxis, Window};
use crate::sparse::densify;
use crate::tflite::{OpCode, TensorType, TfliteModel};
use crate::NnError;

fn err(name: &str, reason: String) -> NnError {
    NnError::Tflite {
        name: name.to_owned(),
        reason,
    }
}

/// Most values one tensor may have (2^26, 256 MiB of f32): a guard against corrupt shapes,
/// checked before anything is allocated. MediaPipe's face networks have under a million.
pub const MAX_TENSOR_VALUES: usize = 1 << 26;

/// Most values a compiled network may hold, its weights and activations together (2^28,
/// 1 GiB of f32): a corrupt model that reuses one large constant many times, or describes huge
/// activations, is an error rather than an allocation that takes all memory.
pub const MAX_NETWORK_VALUES: usize = 1 << 28;

/// The values allocated so far while compiling, against [`MAX_NETWORK_VALUES`].
struct Budget<'a> {
    name: &'a str,
    spent: std::cell::Cell<usize>,
}

impl Budget<'_> {
    /// Counts `values` more, before they are allocated.
    fn charge(&self, values: usize) -> Result<(), NnError> {
        let spent = self.spent.get().saturating_add(values);
        if spent > MAX_NETWORK_VALUES {
            return Err(err(
                self.name,
                format!(
                    "its weights and activations need more than {MAX_NETWORK_VALUES} values \
                     (1 GiB), far more than a face network"
                ),
            ));
        }
        self.spent.set(spent);
        Ok(())
    }
}

impl Network {
    /// Compiles a parsed model. `name` is used in error messages.
    ///
    /// Errors when the graph uses an operator variant the kernels do not implement (fused
    /// activations, dilation, depth multiplier ≠ 1, broadcasting adds, non-constant weights).
    pub fn compile(model: &TfliteModel, name: &str) -> Result<Network, NnError> {
        let n = model.tensors.len();
        // Every shape within MAX_TENSOR_VALUES (zero dimensions counted as one), so that no
        // product of dimensions below can overflow and no tensor is unreasonably large.
        for t in &model.tensors {
            let size = t
                .shape
                .iter()
                .try_fold(1usize, |size, &d| size.checked_mul(d.max(1)));
            if size.is_none_or(|size| size > MAX_TENSOR_VALUES) {
                return Err(err(
                    name,
                    format!(
                        "tensor {} of shape {} is too large: its dimensions multiply to more \
                         than {MAX_TENSOR_VALUES}",
                        t.name,
                        dims(&t.shape)
                    ),
                ));
            }
        }
        let budget = Budget {
            name,
            spent: std::cell::Cell::new(0),
        };
        let shapes: Vec<Vec<usize>> = model.tensors.iter().map(|t| t.shape.clone()).collect();
        // Constant values: float32 buffers directly, float16 through DEQUANTIZE.
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
                let dense = densify(sparsity, &t.shape, &values)
                    .map_err(|e| err(name, format!("sparse tensor {}: {e}", t.name)))?;
                consts[i] = Some(dense);
            }
        }
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
        let mut steps = Vec::new();
        let mut produced = vec![false; n];
        produced[input] = true;
        for (k, op) in model.operators.iter().enumerate() {
            let ctx = |reason: String| err(name, format!("operator {k} ({:?}): {reason}", op.code));
            // Fused activations: RELU on CONV_2D and ADD (their kernels apply it), none elsewhere.
            let act = match (op.options.activation, op.code) {
                (0, _) => Activation::None,
                (1, OpCode::Conv2d | OpCode::Add) => Activation::Relu,
                (a, _) => {
                    return Err(ctx(format!("fused activation {a} not supported")));
                }
            };
            let input = |j: usize| -> Result<usize, NnError> {
                op.inputs
                    .get(j)
                    .and_then(|&t| usize::try_from(t).ok())
                    .ok_or_else(|| ctx(format!("missing input {j}")))
            };
            let Some(&y) = op.outputs.first() else {
                return Err(ctx("no output".into()));
            };
            let constant = |t: usize| -> Result<&Vec<f32>, NnError> {
                let values = consts[t].as_ref().ok_or_else(|| {
                    ctx(format!(
                        "tensor {} must be a constant",
                        model.tensors[t].name
                    ))
                })?;
                // A DEQUANTIZE output takes its input's values, whatever its own shape says.
                let len: usize = shapes[t].iter().product();
                if values.len() != len {
                    return Err(ctx(format!(
                        "constant {} has {} values for its shape {}",
                        model.tensors[t].name,
                        values.len(),
                        dims(&shapes[t])
                    )));
                }
                Ok(values)
            };
            let activation = |t: usize| -> Result<usize, NnError> {
                if produced[t] {
                    Ok(t)
                } else {
                    Err(ctx(format!(
                        "tensor {} is used before it is computed",
                        model.tensors[t].name
                    )))
                }
            };
            let nhwc = |t: usize| -> Result<[usize; 3], NnError> {
                match shapes[t].as_slice() {
                    &[1, h, w, c] => Ok([h, w, c]),
                    s => Err(ctx(format!(
                        "tensor {} has shape {s:?}, expected [1, H, W, C]",
                        model.tensors[t].name
                    ))),
                }
            };
            let step = match op.code {
                OpCode::Dequantize => {
                    let x = input(0)?;
                    let values = constant(x)?;
                    budget.charge(values.len())?;
                    consts[y] = Some(values.clone());
                    continue;
                }
                OpCode::Densify => {
                    // The sparse input was expanded when the constants were read.
                    let x = input(0)?;
                    if model.tensors[x].sparsity.is_none() || shapes[x] != shapes[y] {
                        return Err(ctx(format!(
                            "input {} must be a sparse constant of the output's shape",
                            model.tensors[x].name
                        )));
                    }
                    let values = constant(x)?;
                    budget.charge(values.len())?;
                    consts[y] = Some(values.clone());
                    continue;
                }
                OpCode::Conv2d => {
                    let x = activation(input(0)?)?;
                    let [h, w, ci] = nhwc(x)?;
                    let (kt, bt) = (input(1)?, input(2)?);
                    let (kernel, bias) = (constant(kt)?, constant(bt)?);
                    let &[co, kh, kw, kci] = shapes[kt].as_slice() else {
                        return Err(ctx(format!("kernel shape {:?}", shapes[kt])));
                    };
                    if kci != ci || bias.len() != co || op.options.dilation != [1, 1] {
                        return Err(ctx(format!(
                            "kernel {:?} does not fit input {:?}",
                            shapes[kt], shapes[x]
                        )));
                    }
                    let win = Window::new(h, w, [kh, kw], op.options.stride, op.options.padding);
                    check_out(&ctx, &shapes[y], [win.out_h, win.out_w, co])?;
                    budget.charge(kernel.len() + bias.len())?;
                    let wts = Conv2dWeights::from_ohwi(kernel, co, kh, kw, ci, bias.clone());
                    Step::Conv {
                        x,
                        y,
                        win,
                        wts,
                        act,
                    }
                }
                OpCode::DepthwiseConv2d => {
                    let x = activation(input(0)?)?;
                    let [h, w, c] = nhwc(x)?;
                    let (kt, bt) = (input(1)?, input(2)?);
                    let (kernel, bias) = (constant(kt)?, constant(bt)?);
                    let &[1, kh, kw, kc] = shapes[kt].as_slice() else {
                        return Err(ctx(format!("kernel shape {:?}", shapes[kt])));
                    };
                    if kc != c
                        || bias.len() != c
                        || op.options.depth_multiplier != 1
                        || op.options.dilation != [1, 1]
                    {
                        return Err(ctx(format!(
                            "kernel {:?} does not fit input {:?}",
                            shapes[kt], shapes[x]
                        )));
                    }
                    let win = Window::new(h, w, [kh, kw], op.options.stride, op.options.padding);
                    check_out(&ctx, &shapes[y], [win.out_h, win.out_w, c])?;
                    budget.charge(kernel.len() + bias.len())?;
                    Step::Depthwise {
                        x,
                        y,
                        win,
                        c,
                        w: kernel.clone(),
                        b: bias.clone(),
                    }
                }
                OpCode::Prelu => {
                    let x = activation(input(0)?)?;
                    let alpha = constant(input(1)?)?;
                    budget.charge(alpha.len())?;
                    let alpha = alpha.clone();
                    let c = *shapes[x].last().unwrap_or(&0);
                    if alpha.len() != c || shapes[y] != shapes[x] {
                        return Err(ctx(format!(
                            "alpha of {} values for {c} channels",
                            alpha.len()
                        )));
                    }
                    Step::Prelu { x, y, alpha }
                }
                OpCode::Relu => {
                    let x = activation(input(0)?)?;
                    Step::Relu { x, y }
                }
                OpCode::Add => {
                    let (a, b) = (activation(input(0)?)?, activation(input(1)?)?);
                    if shapes[a] != shapes[b] || shapes[a] != shapes[y] {
                        return Err(ctx(format!(
                            "broadcasting add {:?} + {:?} not supported",
                            shapes[a], shapes[b]
                        )));
                    }
                    Step::Add { a, b, y, act }
                }
                OpCode::ResizeBilinear => {
                    let x = activation(input(0)?)?;
                    let [h, w, c] = nhwc(x)?;
                    let size = ints[input(1)?]
                        .as_ref()
                        .ok_or_else(|| ctx("size must be a constant int32 tensor".into()))?;
                    let &[oh, ow] = size.as_slice() else {
                        return Err(ctx(format!("size {size:?}")));
                    };
                    let (oh, ow) = (usize::try_from(oh), usize::try_from(ow));
                    let (Ok(oh), Ok(ow)) = (oh, ow) else {
                        return Err(ctx(format!("negative size {size:?}")));
                    };
                    if h == 0 || w == 0 {
                        return Err(ctx(format!("empty input {:?}", shapes[x])));
                    }
                    check_out(&ctx, &shapes[y], [oh, ow, c])?;
                    let (ac, hp) = (op.options.align_corners, op.options.half_pixel_centers);
                    if ac && hp {
                        return Err(ctx("align_corners with half_pixel_centers".into()));
                    }
                    // Per output row and column: two indices and a weight, five f32s' worth.
                    budget.charge(5 * (oh + ow))?;
                    Step::Resize {
                        x,
                        y,
                        in_w: w,
                        c,
                        rows: ResizeAxis::new(h, oh, ac, hp),
                        cols: ResizeAxis::new(w, ow, ac, hp),
                    }
                }
                OpCode::DepthToSpace => {
                    let x = activation(input(0)?)?;
                    let [h, w, c] = nhwc(x)?;
                    let block = op.options.block_size;
                    if block < 2 || !c.is_multiple_of(block * block) {
                        return Err(ctx(format!("block size {block} for {c} channels")));
                    }
                    let c_out = c / (block * block);
                    check_out(&ctx, &shapes[y], [h * block, w * block, c_out])?;
                    Step::DepthToSpace {
                        x,
                        y,
                        h,
                        w,
                        c_out,
                        block,
                    }
                }
                OpCode::MaxPool2d => {
                    let x = activation(input(0)?)?;
                    let [h, w, c] = nhwc(x)?;
                    let win = Window::new(
                        h,
                        w,
                        op.options.filter,
                        op.options.stride,
                        op.options.padding,
                    );
                    check_out(&ctx, &shapes[y], [win.out_h, win.out_w, c])?;
                    Step::MaxPool { x, y, win, c }
                }
                OpCode::Pad => {
                    let x = activation(input(0)?)?;
                    let pt = input(1)?;
                    let p = ints[pt]
                        .as_ref()
                        .ok_or_else(|| ctx("paddings must be a constant int32 tensor".into()))?;
                    let shape: [usize; 4] = match shapes[x].as_slice() {
                        &[a, b, c, d] => [a, b, c, d],
                        s => return Err(ctx(format!("pad of a rank-{} tensor", s.len()))),
                    };
                    if p.len() != 8 || p.iter().any(|&v| v < 0) {
                        return Err(ctx(format!("paddings {p:?}")));
                    }
                    let pads: [[usize; 2]; 4] =
                        std::array::from_fn(|d| [p[2 * d] as usize, p[2 * d + 1] as usize]);
                    let out: Vec<usize> =
                        (0..4).map(|d| shape[d] + pads[d][0] + pads[d][1]).collect();
                    if out != shapes[y] {
                        return Err(ctx(format!("padded shape {out:?} ≠ {:?}", shapes[y])));
                    }
                    Step::Pad { x, y, shape, pads }
                }
                OpCode::Reshape => {
                    let x = activation(input(0)?)?;
                    if shapes[x].iter().product::<usize>() != shapes[y].iter().product::<usize>() {
                        return Err(ctx(format!("reshape {:?} → {:?}", shapes[x], shapes[y])));
                    }
                    Step::Copy { x, y }
                }
                OpCode::Concatenation => {
                    let xs = op
                        .inputs
                        .iter()
                        .map(|&t| {
                            usize::try_from(t)
                                .map_err(|_| ctx("absent input".into()))
                                .and_then(activation)
                        })
                        .collect::<Result<Vec<_>, _>>()?;
                    let rank = shapes[y].len() as i32;
                    let axis = if op.options.axis < 0 {
                        op.options.axis + rank
                    } else {
                        op.options.axis
                    };
                    if !(0..rank).contains(&axis) {
                        return Err(ctx(format!("axis {} for rank {rank}", op.options.axis)));
                    }
                    let outer: usize = shapes[y][..axis as usize].iter().product();
                    let total: usize = xs
                        .iter()
                        .map(|&t| shapes[t].iter().product::<usize>())
                        .sum();
                    if total != shapes[y].iter().product::<usize>() {
                        return Err(ctx("concatenated sizes do not add up".into()));
                    }
                    Step::Concat { xs, y, outer }
                }
            };
            produced[y] = true;
            steps.push(step);
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
                Step::Conv { win, wts, .. } => win.k_h * win.k_w * wts.c_in,
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

fn check_out(
    ctx: &dyn Fn(String) -> NnError,
    shape: &[usize],
    hwc: [usize; 3],
) -> Result<(), NnError> {
    if shape == [1, hwc[0], hwc[1], hwc[2]] {
        Ok(())
    } else {
        Err(ctx(format!(
            "output shape {shape:?}, computed [1, {}, {}, {}]",
            hwc[0], hwc[1], hwc[2]
        )))
    }
}

/// Merges each `ADD` without a fused activation whose sum only the next step, a `PRELU`, reads
/// (and which is not an output) into one [`Step::AddPrelu`]: one pass over memory instead of
/// two, the same values.
fn fuse_add_prelu(steps: Vec<Step>, outputs: &[usize]) -> Vec<Step> {
    let mut readers = std::collections::HashMap::<usize, usize>::new();
    for step in &steps {
        for t in step.io().0 {
            *readers.entry(t).or_default() += 1;
        }
    }
    let mut fused = Vec::with_capacity(steps.len());
    let mut it = steps.into_iter().peekable();
    while let Some(step) = it.next() {
        if let Step::Add {
            a,
            b,
            y: sum,
            act: Activation::None,
        } = step
        {
            let only_reader = readers.get(&sum) == Some(&1) && !outputs.contains(&sum);
            if let Some(Step::Prelu { x, .. }) = it.peek() {
                if *x == sum && only_reader {
                    let Some(Step::Prelu { y, alpha, .. }) = it.next() else {
                        unreachable!("peeked")
                    };
                    fused.push(Step::AddPrelu { a, b, y, alpha });
                    continue;
                }
            }
        }
        fused.push(step);
    }
    fused
}
