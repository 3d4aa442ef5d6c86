//! The compiled plan's instruction: one [`Step`] per kernel call, naming the tensors it reads
//! and writes by index (their buffers are assigned by [`super::liveness`]).

use crate::ops::{Activation, Conv2dWeights, ResizeAxis, Window};

/// One compiled operator. Tensor indices refer to [`Network`](super::Network)'s value buffers.
#[derive(Clone, Debug)]
pub(super) enum Step {
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

impl Step {
    /// Tensors read and written by the step: its inputs, then its output.
    pub(super) fn io(&self) -> (Vec<usize>, usize) {
        match self {
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
}
