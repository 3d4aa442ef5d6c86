//! Whole-network tests on hand-built graphs: compiled, run and profiled, with values exact in
//! f32, and the models the compiler must reject.

use super::Network;
use crate::tflite::{OpCode, OpOptions, Operator, Tensor, TensorType, TfliteModel};

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
        custom: None,
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

/// The attention face mesh's operators in a graph of rank-3 tensors and three outputs: four
/// landmarks `x` (`[1, 4, 3]`) halved by `MUL`, a crop's matrix from them
/// (`Landmarks2TransformMatrix`), that matrix scaled element-wise by a `[1, 4, 4]` constant
/// (`MUL`), the landmarks' `(x, y)` (`STRIDED_SLICE`) mapped by it (`TransformLandmarks`), and
/// the landmarks read as a 2×2×3 image cropped by the first matrix
/// (`TransformTensorBilinear`). Every value exact in f32.
fn attention_ops_model() -> TfliteModel {
    use crate::ops::LandmarksToTransformMatrix;
    use crate::tflite::CustomOptions;
    let ints = |v: &[i32]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
    let mut ops = vec![
        op(OpCode::Mul, &[0, 1], 2),
        op(OpCode::Landmarks2TransformMatrix, &[2], 3),
        op(OpCode::Mul, &[4, 3], 5),
        op(OpCode::StridedSlice, &[0, 6, 7, 8], 9),
        op(OpCode::TransformLandmarks, &[9, 5], 10),
        op(OpCode::Reshape, &[0], 11),
        op(OpCode::TransformTensorBilinear, &[11, 3], 12),
    ];
    ops[1].custom = Some(CustomOptions::LandmarksToTransformMatrix(
        LandmarksToTransformMatrix {
            left: 0,
            right: 1,
            target_rotation: 0.0,
            output_size: [2, 2],
            scale: [1.0, 1.0],
            subset: vec![0, 1, 2, 3],
        },
    ));
    ops[6].custom = Some(CustomOptions::TransformTensorBilinear {
        output_size: [2, 2],
    });
    TfliteModel {
        tensors: vec![
            tensor("x", &[1, 4, 3], TensorType::Float32, 0),
            tensor("half", &[1], TensorType::Float32, 1),
            tensor("halved", &[1, 4, 3], TensorType::Float32, 0),
            tensor("matrix", &[1, 4, 4], TensorType::Float32, 0),
            tensor("to_pixels", &[1, 4, 4], TensorType::Float32, 2),
            tensor("matrix_px", &[1, 4, 4], TensorType::Float32, 0),
            tensor("begin", &[3], TensorType::Int32, 3),
            tensor("end", &[3], TensorType::Int32, 4),
            tensor("strides", &[3], TensorType::Int32, 5),
            tensor("xy", &[1, 4, 2], TensorType::Float32, 0),
            tensor("mapped", &[1, 4, 2], TensorType::Float32, 0),
            tensor("image", &[1, 2, 2, 3], TensorType::Float32, 0),
            tensor("crop", &[1, 2, 2, 3], TensorType::Float32, 0),
        ],
        operators: ops,
        inputs: vec![0],
        outputs: vec![10, 12, 3],
        buffers: vec![
            Vec::new(),
            f32_bytes(&[0.5]),
            // MediaPipe's constant: the crop's matrix in 4× its pixels.
            f32_bytes(&[
                1.0, 1.0, 4.0, 4.0, 1.0, 1.0, 4.0, 4.0, 0.25, 0.25, 1.0, 1.0, 0.25, 0.25, 1.0, 1.0,
            ]),
            ints(&[0, 0, 0]),
            ints(&[1, 4, 2]),
            ints(&[1, 1, 1]),
        ],
    }
}

#[test]
fn runs_the_attention_operators_by_hand() {
    let mut net = Network::compile(&attention_ops_model(), "attention").unwrap();
    // The corners of the box [2, 6]², z = 1 … 4.
    let x = [2.0, 2.0, 1.0, 6.0, 2.0, 2.0, 2.0, 6.0, 3.0, 6.0, 6.0, 4.0];
    for _ in 0..2 {
        net.input_mut().copy_from_slice(&x);
        net.run();
        // Halved, the box is [1, 3]², level: a 2×2 crop of it has unit scale and starts at
        // (1, 1).
        let matrix = [
            1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        assert_eq!(net.output(2), Some(("matrix", &matrix[..])));
        // × the constant: the shift ×4, (x, y) → (x + 4, y + 4).
        let mapped = [6.0, 6.0, 10.0, 6.0, 6.0, 10.0, 10.0, 10.0];
        assert_eq!(net.output(0), Some(("mapped", &mapped[..])));
        // The image's pixel (1, 1) is landmark 3; the other crop pixels fall outside.
        let mut crop = [0.0; 12];
        crop[..3].copy_from_slice(&[6.0, 6.0, 4.0]);
        assert_eq!(net.output_named("crop"), Some(&crop[..]));
    }
    let profile = net.profile(1);
    let ops: Vec<&str> = profile.iter().map(|p| p.op.as_str()).collect();
    assert_eq!(
        ops,
        [
            "mul",
            "landmarks-to-matrix",
            "mul",
            "strided-slice",
            "transform-landmarks",
            "copy",
            "transform-tensor"
        ]
    );
}

#[test]
fn rejects_what_the_attention_operators_do_not_implement() {
    use crate::tflite::CustomOptions;
    let reason = |m: &TfliteModel| Network::compile(m, "attention").unwrap_err().to_string();
    // MUL by a constant of three values over [1, 4, 3]: a broadcast along the last axis.
    let mut m = attention_ops_model();
    m.tensors[1].shape = vec![3];
    m.buffers[1] = f32_bytes(&[0.5; 3]);
    assert!(reason(&m).contains("broadcasting mul"), "{}", reason(&m));
    // A slice with an ellipsis.
    let mut m = attention_ops_model();
    m.operators[3].options.slice.ellipsis = 1;
    assert!(reason(&m).contains("ellipsis"), "{}", reason(&m));
    // A slice whose shape is not the output's.
    let mut m = attention_ops_model();
    m.buffers[4] = [1i32, 4, 3].iter().flat_map(|v| v.to_le_bytes()).collect();
    assert!(
        reason(&m).contains("slice of shape [1, 4, 3]"),
        "{}",
        reason(&m)
    );
    // A landmark the input does not have.
    let mut m = attention_ops_model();
    if let Some(CustomOptions::LandmarksToTransformMatrix(o)) = m.operators[1].custom.as_mut() {
        o.subset.push(7);
    }
    assert!(
        reason(&m).contains("landmark 7 outside the 4"),
        "{}",
        reason(&m)
    );
    // A crop of another size than its output, and an operator without its options.
    let mut m = attention_ops_model();
    m.operators[6].custom = Some(CustomOptions::TransformTensorBilinear {
        output_size: [3, 2],
    });
    assert!(
        reason(&m).contains("TransformTensorBilinear"),
        "{}",
        reason(&m)
    );
    let mut m = attention_ops_model();
    m.operators[1].custom = None;
    assert!(reason(&m).contains("no options"), "{}", reason(&m));
    // A matrix of the wrong shape, and mapped points of another shape than the points.
    let mut m = attention_ops_model();
    m.operators[4].inputs = vec![9, 2];
    assert!(
        reason(&m).contains("matrix halved has shape 1×4×3"),
        "{}",
        reason(&m)
    );
    let mut m = attention_ops_model();
    m.tensors[10].shape = vec![1, 8];
    assert!(reason(&m).contains("output shape 1×8"), "{}", reason(&m));
}
