//! MediaPipe's custom operators of the attention face mesh (version 2):
//! `Landmarks2TransformMatrix` (landmarks `[1, N, 3]` → a 4×4 matrix),
//! `TransformTensorBilinear` (a feature map cropped through that matrix) and
//! `TransformLandmarks` (points `[1, N, 2 or 3]` mapped by it).

use super::operands::Operands;
use crate::network::dims::dims;
use crate::network::step::Step;
use crate::tflite::CustomOptions;
use crate::NnError;

/// The shape of a transform matrix.
const MATRIX_SHAPE: [usize; 3] = [1, 4, 4];

/// Tensor `t`, computed, which must have shape `[1, 4, 4]`.
fn matrix(o: &Operands, t: usize) -> Result<usize, NnError> {
    let m = o.activation(t)?;
    if o.shapes[m] != MATRIX_SHAPE {
        return Err(o.error(format!(
            "matrix {} has shape {}, expected 1×4×4",
            o.model.tensors[m].name,
            dims(&o.shapes[m])
        )));
    }
    Ok(m)
}

/// `Landmarks2TransformMatrix`: every landmark its options name must be among the input's.
pub(super) fn landmarks_to_transform_matrix(o: &Operands) -> Result<Step, NnError> {
    let x = o.activation(o.input(0)?)?;
    let Some(CustomOptions::LandmarksToTransformMatrix(op)) = &o.op.custom else {
        return Err(o.error("no options".into()));
    };
    let &[1, n, 3] = o.shapes[x].as_slice() else {
        return Err(o.error(format!(
            "landmarks of shape {}, expected 1×N×3",
            dims(&o.shapes[x])
        )));
    };
    let named = op.subset.iter().chain([&op.left, &op.right]);
    if let Some(i) = named.copied().find(|&i| i >= n) {
        return Err(o.error(format!("landmark {i} outside the {n} landmarks")));
    }
    if o.shapes[o.y] != MATRIX_SHAPE {
        return Err(o.error(format!(
            "output shape {}, expected 1×4×4",
            dims(&o.shapes[o.y])
        )));
    }
    Ok(Step::LandmarksToMatrix {
        x,
        y: o.y,
        op: op.clone(),
    })
}

/// `TransformTensorBilinear`: a `[1, H, W, C]` input and a matrix; the output is
/// `[1, output_height, output_width, C]` of the options.
pub(super) fn transform_tensor_bilinear(o: &Operands) -> Result<Step, NnError> {
    let x = o.activation(o.input(0)?)?;
    let [h, w, c] = o.nhwc(x)?;
    let m = matrix(o, o.input(1)?)?;
    let Some(CustomOptions::TransformTensorBilinear { output_size }) = o.op.custom else {
        return Err(o.error("no options".into()));
    };
    o.check_output([output_size[0], output_size[1], c])?;
    Ok(Step::TransformTensor {
        x,
        matrix: m,
        y: o.y,
        in_hw: [h, w],
        c,
        out_hw: output_size,
    })
}

/// `TransformLandmarks`: points `[1, N, D]` (`D` = 2 or 3) and a matrix; the output has the
/// points' shape.
pub(super) fn transform_landmarks(o: &Operands) -> Result<Step, NnError> {
    let x = o.activation(o.input(0)?)?;
    let m = matrix(o, o.input(1)?)?;
    let &[1, _, d @ (2 | 3)] = o.shapes[x].as_slice() else {
        return Err(o.error(format!(
            "points of shape {}, expected 1×N×2 or 1×N×3",
            dims(&o.shapes[x])
        )));
    };
    if o.shapes[o.y] != o.shapes[x] {
        return Err(o.error(format!(
            "output shape {}, expected the points' {}",
            dims(&o.shapes[o.y]),
            dims(&o.shapes[x])
        )));
    }
    Ok(Step::TransformLandmarks {
        x,
        matrix: m,
        y: o.y,
        dims: d,
    })
}
