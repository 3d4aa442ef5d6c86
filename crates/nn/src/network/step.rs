//! The compiled plan's instruction: one [`Step`] per kernel call, naming the tensors it reads
//! and writes by index (their buffers are assigned by [`super::liveness`]).

use crate::ops::{
    Activation, Conv2dWeights, LandmarksToTransformMatrix, ResizeAxis, StridedSlice, Window,
};

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
    /// `MUL` of two computed tensors of one shape.
    Mul {
        a: usize,
        b: usize,
        y: usize,
    },
    /// `MUL` by a constant: one value for every element, or one per element.
    MulConstant {
        x: usize,
        y: usize,
        c: Vec<f32>,
    },
    StridedSlice {
        x: usize,
        y: usize,
        slice: StridedSlice,
    },
    /// `Landmarks2TransformMatrix`: landmarks `[1, N, 3]` → a 4×4 matrix.
    LandmarksToMatrix {
        x: usize,
        y: usize,
        op: LandmarksToTransformMatrix,
    },
    /// `TransformTensorBilinear`: `x` (`[1, H, W, C]`) cropped through `matrix`.
    TransformTensor {
        x: usize,
        matrix: usize,
        y: usize,
        in_hw: [usize; 2],
        c: usize,
        out_hw: [usize; 2],
    },
    /// `TransformLandmarks`: points `[1, N, dims]` mapped by `matrix`.
    TransformLandmarks {
        x: usize,
        matrix: usize,
        y: usize,
        dims: usize,
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
            | Step::Copy { x, y }
            | Step::MulConstant { x, y, .. }
            | Step::StridedSlice { x, y, .. }
            | Step::LandmarksToMatrix { x, y, .. } => (vec![*x], *y),
            Step::Add { a, b, y, .. } | Step::AddPrelu { a, b, y, .. } | Step::Mul { a, b, y } => {
                (vec![*a, *b], *y)
            }
            Step::TransformTensor { x, matrix, y, .. }
            | Step::TransformLandmarks { x, matrix, y, .. } => (vec![*x, *matrix], *y),
            Step::Concat { xs, y, .. } => (xs.clone(), *y),
        }
    }
}
