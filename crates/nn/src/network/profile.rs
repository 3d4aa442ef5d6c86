//! Where a run's time goes: [`Network::profile`] times each compiled step alone and sets it
//! against its multiply-adds and the bytes it must move (a roofline per layer).

use super::dims::dims;
use super::run::Network;
use super::step::Step;
use crate::ops::{Activation, Window};

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

impl Network {
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
                let (_, y) = step.io();
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
}

/// A step's kernel in words, its multiply-adds and the f32 values it moves at least.
fn step_cost(step: &Step, len_of: &[usize]) -> (String, u64, u64) {
    let (inputs, y) = step.io();
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
        Step::Mul { .. } => ("mul".into(), len_of[y], 0),
        Step::MulConstant { c, .. } => ("mul".into(), len_of[y], c.len()),
        Step::StridedSlice { .. } => ("strided-slice".into(), 0, 0),
        // Per subset landmark: a turn (four multiplies).
        Step::LandmarksToMatrix { op, .. } => {
            ("landmarks-to-matrix".into(), 4 * op.subset.len(), 0)
        }
        Step::TransformTensor { .. } => ("transform-tensor".into(), 4 * len_of[y], 0),
        Step::TransformLandmarks { .. } => ("transform-landmarks".into(), 2 * len_of[y], 0),
    };
    (op, macs as u64, (io + weights) as u64)
}
