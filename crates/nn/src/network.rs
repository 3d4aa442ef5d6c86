//! The graph compiler and runner: a TFLite graph is compiled once into a list of kernel calls
//! over pre-allocated buffers, then run per input without allocating.
//!
//! Why not tract: `tract-tflite` 0.23 refuses MediaPipe's face networks (no `DEQUANTIZE`, no
//! `PRELU`, registry not extensible). Those networks use thirteen operators, all NHWC with batch
//! 1, so the engine expands the sparse `DENSIFY` constants and folds the float16 `DEQUANTIZE`
//! constants to f32 at load time, re-lays out
//! convolution weights for channel-contiguous inner loops and runs the hand-written kernels of
//! [`crate::ops`].

use crate::float16::f16_slice_to_f32;
use crate::ops::{self, Activation, Conv2dWeights, Fused, Madd, Plain, ResizeAxis, Window};
use crate::sparse::densify;
use crate::tflite::{OpCode, TensorType, TfliteModel};
use crate::NnError;

/// One compiled operator. Tensor indices refer to [`Network`]'s value buffers.
#[derive(Clone, Debug)]
enum Step {
    Conv {
        x: usize,
        y: usize,
        win: Window,
        wts: Conv2dWeights,
        act: Activation,
    },
    Depthwise {
        x: usize,
        y: usize,
        win: Window,
        c: usize,
        w: Vec<f32>,
        b: Vec<f32>,
    },
    Prelu {
        x: usize,
        y: usize,
        alpha: Vec<f32>,
    },
    Relu {
        x: usize,
        y: usize,
    },
    Add {
        a: usize,
        b: usize,
        y: usize,
        act: Activation,
    },
    /// An `ADD` (no fused activation) and the `PRELU` that is its sum's only reader.
    AddPrelu {
        a: usize,
        b: usize,
        y: usize,
        alpha: Vec<f32>,
    },
    Resize {
        x: usize,
        y: usize,
        in_w: usize,
        c: usize,
        rows: ResizeAxis,
        cols: ResizeAxis,
    },
    DepthToSpace {
        x: usize,
        y: usize,
        h: usize,
        w: usize,
        c_out: usize,
        block: usize,
    },
    MaxPool {
        x: usize,
        y: usize,
        win: Window,
        c: usize,
    },
    Pad {
        x: usize,
        y: usize,
        shape: [usize; 4],
        pads: [[usize; 2]; 4],
    },
    Copy {
        x: usize,
        y: usize,
    },
    Concat {
        xs: Vec<usize>,
        y: usize,
        outer: usize,
    },
}

/// A compiled network: run with [`Network::run`], read outputs with [`Network::output`].
#[derive(Clone, Debug)]
pub struct Network {
    steps: Vec<Step>,
    /// Activation buffers ("slots"), shared by tensors whose lifetimes do not overlap so that
    /// the working set stays in cache.
    values: Vec<Vec<f32>>,
    /// Slot of each tensor (meaningful for computed tensors only).
    slot_of: Vec<usize>,
    /// Number of values of each tensor.
    len_of: Vec<usize>,
    shapes: Vec<Vec<usize>>,
    names: Vec<String>,
    input: usize,
    outputs: Vec<usize>,
    scratch: Vec<f32>,
}

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

/// A shape in words, e.g. `1×192×192×3` (`scalar` for rank 0).
fn dims(shape: &[usize]) -> String {
    if shape.is_empty() {
        return "scalar".into();
    }
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    dims.join("×")
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

    /// Shape of the (single) input tensor, e.g. `[1, 192, 192, 3]`.
    pub fn input_shape(&self) -> &[usize] {
        &self.shapes[self.input]
    }

    /// Mutable access to the input tensor (NHWC, f32) to fill it in place before [`Network::run`].
    pub fn input_mut(&mut self) -> &mut [f32] {
        &mut self.values[self.slot_of[self.input]][..self.len_of[self.input]]
    }

    /// Runs the graph on the current input tensor.
    ///
    /// On x86-64 CPUs with AVX2 the same kernels are compiled a second time for 256-bit vectors
    /// and chosen at run time; results agree to float rounding.
    pub fn run(&mut self) {
        self.run_range(0..self.steps.len());
    }

    /// Runs steps `range` of the compiled graph (all of them: [`Network::run`]).
    fn run_range(&mut self, range: std::ops::Range<usize>) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: `run_avx2_fma` is compiled for AVX2 and FMA, and the run-time check just
            // above found both on this CPU; it is otherwise safe code (bounds-checked kernels).
            unsafe { self.run_avx2_fma(range) };
            return;
        }
        self.run_steps::<Plain>(range);
    }

    /// [`Network::run_steps`] with fused multiply-adds, compiled for AVX2 and FMA; call it only
    /// where the CPU has both.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn run_avx2_fma(&mut self, range: std::ops::Range<usize>) {
        self.run_steps::<Fused>(range);
    }

    /// Where a run's time goes: each compiled step timed alone (the median over `runs` runs of
    /// the whole graph, one step at a time, on the current input), with its multiply-adds and
    /// the bytes it must move at least (its inputs, output and weights, once each) — a roofline
    /// per layer. The outputs afterwards are those of an ordinary [`Network::run`].
    pub fn profile(&mut self, runs: usize) -> Vec<StepProfile> {
        let n = self.steps.len();
        let mut times = vec![Vec::with_capacity(runs.max(1)); n];
        for _ in 0..runs.max(1) {
            for (i, t) in times.iter_mut().enumerate() {
                let start = std::time::Instant::now();
                self.run_range(i..i + 1);
                t.push(start.elapsed().as_secs_f64() * 1e6);
            }
        }
        self.steps
            .iter()
            .zip(times)
            .map(|(step, mut t)| {
                t.sort_by(f64::total_cmp);
                let (op, macs, values) = step_cost(step, &self.len_of);
                let (_, y) = step_io(step);
                StepProfile {
                    op,
                    output: dims(&self.shapes[y]),
                    macs,
                    bytes: 4 * values,
                    median_us: t[t.len() / 2],
                }
            })
            .collect()
    }

    #[inline(always)]
    fn run_steps<M: Madd>(&mut self, range: std::ops::Range<usize>) {
        for step in &self.steps[range] {
            let values = &mut self.values;
            let (slot, len) = (&self.slot_of, &self.len_of);
            macro_rules! with_out {
                ($y:expr, |$out:ident| $e:expr) => {{
                    let mut buf = std::mem::take(&mut values[slot[$y]]);
                    {
                        let $out = &mut buf[..len[$y]];
                        $e;
                    }
                    values[slot[$y]] = buf;
                }};
            }
            macro_rules! get {
                ($t:expr) => {
                    &values[slot[$t]][..len[$t]]
                };
            }
            match step {
                Step::Conv {
                    x,
                    y,
                    win,
                    wts,
                    act,
                } => {
                    with_out!(*y, |out| ops::conv2d::<M>(
                        get!(*x),
                        win,
                        wts,
                        *act,
                        &mut self.scratch,
                        out
                    ))
                }
                Step::Depthwise { x, y, win, c, w, b } => {
                    with_out!(*y, |out| ops::depthwise_conv2d::<M>(
                        get!(*x),
                        win,
                        *c,
                        w,
                        b,
                        out
                    ))
                }
                Step::Prelu { x, y, alpha } => {
                    with_out!(*y, |out| ops::separately::prelu(get!(*x), alpha, out))
                }
                Step::Relu { x, y } => with_out!(*y, |out| ops::relu(get!(*x), out)),
                Step::Add { a, b, y, act } => {
                    with_out!(*y, |out| ops::separately::add(
                        get!(*a),
                        get!(*b),
                        *act,
                        out
                    ))
                }
                Step::AddPrelu { a, b, y, alpha } => {
                    with_out!(*y, |out| ops::separately::add_prelu(
                        get!(*a),
                        get!(*b),
                        alpha,
                        out
                    ))
                }
                Step::Resize {
                    x,
                    y,
                    in_w,
                    c,
                    rows,
                    cols,
                } => with_out!(*y, |out| ops::resize_bilinear(
                    get!(*x),
                    *in_w,
                    *c,
                    rows,
                    cols,
                    out
                )),
                Step::DepthToSpace {
                    x,
                    y,
                    h,
                    w,
                    c_out,
                    block,
                } => with_out!(*y, |out| ops::depth_to_space(
                    get!(*x),
                    *h,
                    *w,
                    *c_out,
                    *block,
                    out
                )),
                Step::MaxPool { x, y, win, c } => {
                    with_out!(*y, |out| ops::separately::max_pool2d(
                        get!(*x),
                        win,
                        *c,
                        out
                    ))
                }
                Step::Pad { x, y, shape, pads } => {
                    with_out!(*y, |out| ops::pad4(get!(*x), *shape, *pads, out))
                }
                Step::Copy { x, y } => with_out!(*y, |out| out.copy_from_slice(get!(*x))),
                Step::Concat { xs, y, outer } => with_out!(*y, |out| {
                    let mut pos = 0;
                    for o in 0..*outer {
                        for &t in xs {
                            let chunk = len[t] / outer;
                            out[pos..pos + chunk]
                                .copy_from_slice(&get!(t)[o * chunk..(o + 1) * chunk]);
                            pos += chunk;
                        }
                    }
                }),
            }
        }
    }

    /// Output `k` (in the model's output order) after [`Network::run`], with its tensor name.
    pub fn output(&self, k: usize) -> Option<(&str, &[f32])> {
        let &t = self.outputs.get(k)?;
        Some((
            &self.names[t],
            &self.values[self.slot_of[t]][..self.len_of[t]],
        ))
    }

    /// Output tensor by name, e.g. `"conv2d_21"`.
    pub fn output_named(&self, name: &str) -> Option<&[f32]> {
        self.outputs
            .iter()
            .find(|&&t| self.names[t] == name)
            .map(|&t| &self.values[self.slot_of[t]][..self.len_of[t]])
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

/// Tensors read and written by a step.
/// One compiled step's cost ([`Network::profile`]).
#[derive(Clone, Debug, PartialEq)]
pub struct StepProfile {
    /// The kernel, e.g. `conv 1×1` or `depthwise 3×3/2`.
    pub op: String,
    /// The output's shape, e.g. `1×48×48×32`.
    pub output: String,
    /// Multiply-adds (for element-wise steps: one per output value).
    pub macs: u64,
    /// Bytes the step must read and write at least: inputs, output and weights once each.
    pub bytes: u64,
    /// Median time of the step alone (µs).
    pub median_us: f64,
}

/// A step's kernel in words, its multiply-adds and the f32 values it moves at least.
fn step_cost(step: &Step, len_of: &[usize]) -> (String, u64, u64) {
    let (inputs, y) = step_io(step);
    let io = inputs.iter().map(|&t| len_of[t]).sum::<usize>() + len_of[y];
    let window = |w: &Window| {
        let stride = if w.stride_h == 1 {
            String::new()
        } else {
            format!("/{}", w.stride_h)
        };
        format!("{}×{}{stride}", w.k_h, w.k_w)
    };
    let (op, macs, weights) = match step {
        Step::Conv { win, wts, act, .. } => {
            let relu = if *act == Activation::Relu {
                "+relu"
            } else {
                ""
            };
            let red = win.k_h * win.k_w * wts.c_in;
            (
                format!("conv {}{relu}", window(win)),
                len_of[y] * red,
                wts.w.len() + wts.bias.len(),
            )
        }
        Step::Depthwise { win, w, b, .. } => (
            format!("depthwise {}", window(win)),
            len_of[y] * win.k_h * win.k_w,
            w.len() + b.len(),
        ),
        Step::Prelu { alpha, .. } => ("prelu".into(), len_of[y], alpha.len()),
        Step::Relu { .. } => ("relu".into(), len_of[y], 0),
        Step::Add { act, .. } => {
            let relu = if *act == Activation::Relu {
                "+relu"
            } else {
                ""
            };
            (format!("add{relu}"), len_of[y], 0)
        }
        Step::AddPrelu { alpha, .. } => ("add+prelu".into(), 2 * len_of[y], alpha.len()),
        Step::Resize { .. } => ("resize".into(), 4 * len_of[y], 0),
        Step::DepthToSpace { .. } => ("depth-to-space".into(), 0, 0),
        Step::MaxPool { win, .. } => (
            format!("max-pool {}", window(win)),
            len_of[y] * win.k_h * win.k_w,
            0,
        ),
        Step::Pad { .. } => ("pad".into(), 0, 0),
        Step::Copy { .. } => ("copy".into(), 0, 0),
        Step::Concat { .. } => ("concat".into(), 0, 0),
    };
    (op, macs as u64, (io + weights) as u64)
}

fn step_io(step: &Step) -> (Vec<usize>, usize) {
    match step {
        Step::Conv { x, y, .. }
        | Step::Depthwise { x, y, .. }
        | Step::Prelu { x, y, .. }
        | Step::Relu { x, y }
        | Step::MaxPool { x, y, .. }
        | Step::Pad { x, y, .. }
        | Step::Resize { x, y, .. }
        | Step::DepthToSpace { x, y, .. }
        | Step::Copy { x, y } => (vec![*x], *y),
        Step::Add { a, b, y, .. } | Step::AddPrelu { a, b, y, .. } => (vec![*a, *b], *y),
        Step::Concat { xs, y, .. } => (xs.clone(), *y),
    }
}

/// Merges each `ADD` without a fused activation whose sum only the next step, a `PRELU`, reads
/// (and which is not an output) into one [`Step::AddPrelu`]: one pass over memory instead of
/// two, the same values.
fn fuse_add_prelu(steps: Vec<Step>, outputs: &[usize]) -> Vec<Step> {
    let mut readers = std::collections::HashMap::<usize, usize>::new();
    for step in &steps {
        for t in step_io(step).0 {
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

/// Liveness-based buffer sharing: each computed tensor gets a slot that no tensor alive at the
/// same time uses (best fit among the free slots, grown when needed). The graph input and
/// outputs keep their slots for the whole run. Returns the slot of each tensor and each slot's
/// length.
fn allocate_slots(
    steps: &[Step],
    len_of: &[usize],
    input: usize,
    outputs: &[usize],
) -> (Vec<usize>, Vec<usize>) {
    let n = len_of.len();
    let mut last_use = vec![0usize; n];
    for (k, step) in steps.iter().enumerate() {
        for t in step_io(step).0 {
            last_use[t] = k;
        }
    }
    let pinned = |t: usize| t == input || outputs.contains(&t);
    let mut slot_of = vec![0usize; n];
    let mut slot_len = vec![len_of[input]];
    let mut free: Vec<usize> = Vec::new();
    for (k, step) in steps.iter().enumerate() {
        let (reads, y) = step_io(step);
        let need = len_of[y];
        let best = free
            .iter()
            .enumerate()
            .filter(|&(_, &s)| slot_len[s] >= need)
            .min_by_key(|&(_, &s)| slot_len[s])
            .map(|(i, _)| i)
            .or_else(|| (!free.is_empty()).then(|| free.len() - 1));
        let s = match best {
            Some(i) => free.swap_remove(i),
            None => {
                slot_len.push(0);
                slot_len.len() - 1
            }
        };
        slot_len[s] = slot_len[s].max(need);
        slot_of[y] = s;
        for t in reads {
            if last_use[t] == k && !pinned(t) && !free.contains(&slot_of[t]) {
                free.push(slot_of[t]);
            }
        }
    }
    (slot_of, slot_len)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tflite::{OpOptions, Operator, Tensor};

    fn tensor(name: &str, shape: &[usize], dtype: TensorType, buffer: usize) -> Tensor {
        Tensor {
            name: name.into(),
            shape: shape.to_vec(),
            dtype,
            buffer,
            sparsity: None,
        }
    }

    fn op(code: OpCode, inputs: &[i32], output: usize) -> Operator {
        Operator {
            code,
            inputs: inputs.to_vec(),
            outputs: vec![output],
            options: OpOptions::default(),
        }
    }

    fn f32_bytes(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    /// `x → conv1×1 (float16 kernel behind DEQUANTIZE) → PReLU → + x → reshape`, values exact
    /// in f32.
    fn small_model() -> TfliteModel {
        let f16: Vec<u8> = [0x3c00u16, 0, 0, 0xbc00] // [[1, 0], [0, −1]] as [C_out, 1, 1, C_in]
            .iter()
            .flat_map(|h| h.to_le_bytes())
            .collect();
        TfliteModel {
            tensors: vec![
                tensor("x", &[1, 2, 2, 2], TensorType::Float32, 0),
                tensor("k16", &[2, 1, 1, 2], TensorType::Float16, 1),
                tensor("k", &[2, 1, 1, 2], TensorType::Float32, 0),
                tensor("bias", &[2], TensorType::Float32, 2),
                tensor("conv", &[1, 2, 2, 2], TensorType::Float32, 0),
                tensor("alpha", &[1, 1, 2], TensorType::Float32, 3),
                tensor("prelu", &[1, 2, 2, 2], TensorType::Float32, 0),
                tensor("sum", &[1, 2, 2, 2], TensorType::Float32, 0),
                tensor("flat", &[1, 8], TensorType::Float32, 0),
            ],
            operators: vec![
                op(OpCode::Dequantize, &[1], 2),
                op(OpCode::Conv2d, &[0, 2, 3], 4),
                op(OpCode::Prelu, &[4, 5], 6),
                op(OpCode::Add, &[0, 6], 7),
                op(OpCode::Reshape, &[7, -1], 8),
            ],
            inputs: vec![0],
            outputs: vec![8],
            buffers: vec![
                Vec::new(),
                f16,
                f32_bytes(&[0.5, 0.0]),
                f32_bytes(&[0.25, 0.5]),
            ],
        }
    }

    #[test]
    fn runs_a_hand_built_graph_exactly_and_repeatably() {
        let mut net = Network::compile(&small_model(), "small").unwrap();
        assert_eq!(net.input_shape(), [1, 2, 2, 2]);
        let x = [1.0, 2.0, -3.0, 4.0, 0.0, -1.0, 2.0, 2.0];
        // conv: (x0 + 0.5, −x1); PReLU: negatives × (0.25, 0.5); then + x.
        let expected = [2.5, 1.0, -3.625, 2.0, 0.5, 0.0, 4.5, 1.0];
        for _ in 0..2 {
            net.input_mut().copy_from_slice(&x);
            net.run();
            assert_eq!(net.output(0), Some(("flat", &expected[..])));
            assert_eq!(net.output_named("flat"), Some(&expected[..]));
        }
        assert!(net.output(1).is_none() && net.output_named("sum").is_none());
    }

    /// `x + x → PReLU`: one fused step when only the PReLU reads the sum, two when the sum is
    /// also an output; the same values either way.
    #[test]
    fn an_add_read_only_by_a_prelu_runs_fused() {
        let model = |outputs: Vec<usize>| TfliteModel {
            tensors: vec![
                tensor("x", &[1, 1, 2, 2], TensorType::Float32, 0),
                tensor("alpha", &[1, 1, 2], TensorType::Float32, 1),
                tensor("sum", &[1, 1, 2, 2], TensorType::Float32, 0),
                tensor("out", &[1, 1, 2, 2], TensorType::Float32, 0),
            ],
            operators: vec![op(OpCode::Add, &[0, 0], 2), op(OpCode::Prelu, &[2, 1], 3)],
            inputs: vec![0],
            outputs,
            buffers: vec![Vec::new(), f32_bytes(&[0.5, 0.25])],
        };
        let x = [1.0, -2.0, -3.0, 0.5];
        let expected = [2.0, -1.0, -3.0, 1.0];
        let mut fused = Network::compile(&model(vec![3]), "fused").unwrap();
        assert_eq!(fused.steps.len(), 1);
        fused.input_mut().copy_from_slice(&x);
        fused.run();
        assert_eq!(fused.output_named("out"), Some(&expected[..]));
        assert_eq!(fused.profile(1)[0].op, "add+prelu");
        let mut both = Network::compile(&model(vec![2, 3]), "both").unwrap();
        assert_eq!(both.steps.len(), 2);
        both.input_mut().copy_from_slice(&x);
        both.run();
        assert_eq!(both.output_named("out"), Some(&expected[..]));
        assert_eq!(both.output_named("sum"), Some(&[2.0, -4.0, -6.0, 1.0][..]));
    }

    /// The full-range detector's operators: a sparse float16 kernel behind `DENSIFY` and
    /// `DEQUANTIZE`, `CONV_2D` with fused ReLU, `DEPTH_TO_SPACE`, `RESIZE_BILINEAR` (half-pixel)
    /// and `ADD` with fused ReLU; every value exact in f32.
    fn full_range_ops_model() -> TfliteModel {
        use crate::sparse::{DimFormat, Sparsity};
        let f16: Vec<u8> = [0x3c00u16, 0xbc00, 0x4000] // 1, −1, 2
            .iter()
            .flat_map(|h| h.to_le_bytes())
            .collect();
        let mut sparse = tensor("k16s", &[4, 1, 1, 1], TensorType::Float16, 1);
        // Kernel [1, 0, −1, 2] over [C_out, 1, 1, C_in = 1]; channel 1's zero is not stored.
        sparse.sparsity = Some(Sparsity {
            traversal_order: vec![0, 1, 2, 3],
            block_map: Vec::new(),
            dim_metadata: vec![
                DimFormat::Dense { size: 4 },
                DimFormat::Dense { size: 1 },
                DimFormat::Dense { size: 1 },
                DimFormat::SparseCsr {
                    segments: vec![0, 1, 1, 2, 3],
                    indices: vec![0, 0, 0],
                },
            ],
        });
        let mut ops = vec![
            op(OpCode::Densify, &[1], 2),
            op(OpCode::Dequantize, &[2], 3),
            op(OpCode::Conv2d, &[0, 3, 4], 5),
            op(OpCode::DepthToSpace, &[5], 6),
            op(OpCode::ResizeBilinear, &[6, 7], 8),
            op(OpCode::Conv2d, &[8, 9, 10], 11),
            op(OpCode::Add, &[8, 11], 12),
        ];
        ops[2].options.activation = 1;
        ops[3].options.block_size = 2;
        ops[4].options.half_pixel_centers = true;
        ops[6].options.activation = 1;
        TfliteModel {
            tensors: vec![
                tensor("x", &[1, 1, 2, 1], TensorType::Float32, 0),
                sparse,
                tensor("k16", &[4, 1, 1, 1], TensorType::Float16, 0),
                tensor("k", &[4, 1, 1, 1], TensorType::Float32, 0),
                tensor("bias4", &[4], TensorType::Float32, 2),
                tensor("conv", &[1, 1, 2, 4], TensorType::Float32, 0),
                tensor("d2s", &[1, 2, 4, 1], TensorType::Float32, 0),
                tensor("size", &[2], TensorType::Int32, 3),
                tensor("resized", &[1, 4, 4, 1], TensorType::Float32, 0),
                tensor("k2", &[1, 1, 1, 1], TensorType::Float32, 4),
                tensor("bias1", &[1], TensorType::Float32, 5),
                tensor("conv2", &[1, 4, 4, 1], TensorType::Float32, 0),
                tensor("sum", &[1, 4, 4, 1], TensorType::Float32, 0),
            ],
            operators: ops,
            inputs: vec![0],
            outputs: vec![12],
            buffers: vec![
                Vec::new(),
                f16,
                f32_bytes(&[0.0; 4]),
                [4i32, 4].iter().flat_map(|v| v.to_le_bytes()).collect(),
                f32_bytes(&[-2.0]),
                f32_bytes(&[1.0]),
            ],
        }
    }

    #[test]
    fn runs_the_full_range_operators_by_hand() {
        let mut net = Network::compile(&full_range_ops_model(), "ops").unwrap();
        net.input_mut().copy_from_slice(&[1.0, -2.0]);
        net.run();
        // conv + ReLU: pixel 0 → [1, 0, 0, 2], pixel 1 → [0, 0, 2, 0]; depth-to-space (DCR):
        // rows r0 = [1, 0, 0, 0], r1 = [0, 2, 2, 0]; resize rows 2 → 4 (half-pixel): r0,
        // r0 + ¼(r1 − r0), r0 + ¾(r1 − r0), r1 (columns 4 → 4 unchanged); then
        // ReLU(r + (1 − 2r)) = max(1 − r, 0).
        let expected = [
            0.0, 1.0, 1.0, 1.0, //
            0.25, 0.5, 0.5, 1.0, //
            0.75, 0.0, 0.0, 1.0, //
            1.0, 0.0, 0.0, 1.0,
        ];
        assert_eq!(net.output(0), Some(("sum", &expected[..])));

        // A sparse kernel whose indices leave the tensor is an error naming the file.
        let mut m = full_range_ops_model();
        if let Some(s) = m.tensors[1].sparsity.as_mut() {
            s.dim_metadata[3] = crate::sparse::DimFormat::SparseCsr {
                segments: vec![0, 1, 1, 2, 3],
                indices: vec![0, 1, 0],
            };
        }
        let e = Network::compile(&m, "sparse.tflite")
            .unwrap_err()
            .to_string();
        assert!(e.contains("sparse.tflite") && e.contains("k16s"), "{e}");
        // So is one that places more values than stored, and a size that is not the output's.
        let mut m = full_range_ops_model();
        m.buffers[1].truncate(4);
        assert!(Network::compile(&m, "short").is_err());
        let mut m = full_range_ops_model();
        m.buffers[3] = [4i32, 5].iter().flat_map(|v| v.to_le_bytes()).collect();
        let e = Network::compile(&m, "size").unwrap_err().to_string();
        assert!(e.contains("ResizeBilinear"), "{e}");
        // Fused activations elsewhere (here on DEPTH_TO_SPACE) stay unsupported.
        let mut m = full_range_ops_model();
        m.operators[3].options.activation = 1;
        assert!(Network::compile(&m, "d2s").is_err());
    }

    #[test]
    fn rejects_what_the_kernels_do_not_implement() {
        let mut m = small_model();
        m.operators[1].options.activation = 3; // RELU6
        let e = Network::compile(&m, "fused.tflite")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("fused.tflite") && e.contains("fused activation"),
            "{e}"
        );

        let mut m = small_model();
        m.tensors[1].dtype = TensorType::Other(9);
        let e = Network::compile(&m, "int8").unwrap_err().to_string();
        assert!(e.contains("unsupported type 9"), "{e}");

        let mut m = small_model();
        m.tensors[5].shape = vec![1, 2, 2, 2];
        m.buffers[3] = f32_bytes(&[0.25; 8]);
        assert!(Network::compile(&m, "broadcast").is_err());

        let mut m = small_model();
        m.operators.swap(2, 3);
        let e = Network::compile(&m, "order").unwrap_err().to_string();
        assert!(e.contains("used before it is computed"), "{e}");
    }

    #[test]
    fn shapes_too_large_to_hold_are_rejected_before_allocating() {
        // A constant whose dimensions multiply past usize (this used to panic on the product).
        let mut m = small_model();
        m.tensors[5].shape = vec![1 << 32, 1 << 32];
        let e = Network::compile(&m, "huge.tflite").unwrap_err().to_string();
        assert!(
            e.contains("huge.tflite") && e.contains("alpha") && e.contains("too large"),
            "{e}"
        );
        // An activation of 2^40 values.
        let mut m = small_model();
        m.tensors[4].shape = vec![1, 1 << 20, 1 << 20, 1];
        let e = Network::compile(&m, "big").unwrap_err().to_string();
        assert!(e.contains("conv of shape 1×1048576×1048576×1"), "{e}");
    }

    #[test]
    fn a_constant_must_have_the_values_its_shape_says() {
        // DEQUANTIZE hands its input's 4 values to a kernel of shape 3×1×1×2 (the convolution
        // used to read past them).
        let mut m = small_model();
        m.tensors[2].shape = vec![3, 1, 1, 2];
        let e = Network::compile(&m, "short").unwrap_err().to_string();
        assert!(
            e.contains("constant k has 4 values for its shape 3×1×1×2"),
            "{e}"
        );
    }

    #[test]
    fn activations_past_the_memory_limit_are_rejected_before_allocating() {
        // Six live tensors of 2^26 values (the input and five outputs): 1.5 GiB in all.
        let side = 1 << 13;
        let mut tensors = vec![tensor("x", &[1, side, side, 1], TensorType::Float32, 0)];
        let mut operators = Vec::new();
        for k in 1..=5 {
            tensors.push(tensor(
                &format!("y{k}"),
                &[1, side, side, 1],
                TensorType::Float32,
                0,
            ));
            operators.push(op(OpCode::Relu, &[0], k));
        }
        let model = TfliteModel {
            tensors,
            operators,
            inputs: vec![0],
            outputs: (1..=5).collect(),
            buffers: vec![Vec::new()],
        };
        let e = Network::compile(&model, "wide.tflite")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("wide.tflite") && e.contains("weights and activations need more than"),
            "{e}"
        );
    }

    #[test]
    fn a_graph_of_more_than_one_input_is_rejected() {
        // A second input listed as an output had no buffer of its own: reading that output
        // used to index past the first input's buffer.
        let mut m = small_model();
        m.tensors
            .push(tensor("second", &[1, 64], TensorType::Float32, 0));
        m.inputs.push(9);
        m.outputs.push(9);
        let e = Network::compile(&m, "two_inputs.tflite")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("two_inputs.tflite") && e.contains("the graph has 2 inputs"),
            "{e}"
        );
    }
}
