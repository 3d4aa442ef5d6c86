//! The compiled [`Network`] and running it: the steps over the activation buffers, the input
//! filled in place, the step loop (a second build with AVX2 and FMA chosen at run time), the
//! outputs read back. Nothing here allocates.

use super::step::Step;
use crate::ops::{self, Fused, Madd, Plain};

/// A compiled network: run with [`Network::run`], read outputs with [`Network::output`].
#[derive(Clone, Debug)]
pub struct Network {
    pub(super) steps: Vec<Step>,
    /// Activation buffers ("slots"), shared by tensors whose lifetimes do not overlap so that
    /// the working set stays in cache.
    pub(super) values: Vec<Vec<f32>>,
    /// Slot of each tensor (meaningful for computed tensors only).
    pub(super) slot_of: Vec<usize>,
    /// Number of values of each tensor.
    pub(super) len_of: Vec<usize>,
    pub(super) shapes: Vec<Vec<usize>>,
    pub(super) names: Vec<String>,
    pub(super) input: usize,
    pub(super) outputs: Vec<usize>,
    pub(super) scratch: Vec<f32>,
}

impl Network {
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
    pub(super) fn run_range(&mut self, range: std::ops::Range<usize>) {
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
                Step::Mul { a, b, y } => with_out!(*y, |out| ops::mul(get!(*a), get!(*b), out)),
                Step::MulConstant { x, y, c } => with_out!(*y, |out| ops::mul(get!(*x), c, out)),
                Step::StridedSlice { x, y, slice } => {
                    with_out!(*y, |out| ops::strided_slice(get!(*x), slice, out))
                }
                Step::LandmarksToMatrix { x, y, op } => {
                    with_out!(*y, |out| ops::landmarks_to_transform_matrix(
                        get!(*x),
                        op,
                        out
                    ))
                }
                Step::TransformTensor {
                    x,
                    matrix,
                    y,
                    in_hw,
                    c,
                    out_hw,
                } => with_out!(*y, |out| ops::transform_tensor_bilinear(
                    get!(*x),
                    *in_hw,
                    *c,
                    get!(*matrix),
                    *out_hw,
                    out
                )),
                Step::TransformLandmarks { x, matrix, y, dims } => {
                    with_out!(*y, |out| ops::transform_landmarks(
                        get!(*x),
                        *dims,
                        get!(*matrix),
                        out
                    ))
                }
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
