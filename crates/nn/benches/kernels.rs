//! Convolution kernels per call, single thread, on random data (fixed seed), through one-operator
//! networks so that the run-time instruction-set dispatch of `Network::run` is what is measured.
//! Shapes are those of typical layers of MediaPipe's landmark network; no model file is needed.

use criterion::{criterion_group, criterion_main, Criterion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use visage_nn::tflite::{OpCode, OpOptions, Operator, Padding, Tensor, TensorType};
use visage_nn::{Network, TfliteModel};

fn random_bytes(rng: &mut ChaCha8Rng, n: usize) -> Vec<u8> {
    (0..n)
        .flat_map(|_| rng.random_range(-1.0f32..1.0).to_le_bytes())
        .collect()
}

/// A network of one `CONV_2D` (`depthwise: false`, `C_out` = `c_out`) or `DEPTHWISE_CONV_2D`
/// (`C_out` = `C_in`) with `SAME` padding over an `[h, w, c_in]` input.
fn one_conv(
    rng: &mut ChaCha8Rng,
    [h, w, c_in]: [usize; 3],
    k: usize,
    stride: usize,
    depthwise: bool,
    c_out: usize,
) -> Network {
    let c_out = if depthwise { c_in } else { c_out };
    let kernel_shape = if depthwise {
        vec![1, k, k, c_in]
    } else {
        vec![c_out, k, k, c_in]
    };
    let kernel_len: usize = kernel_shape.iter().product();
    let tensor = |name: &str, shape: Vec<usize>, buffer: usize| Tensor {
        name: name.into(),
        shape,
        dtype: TensorType::Float32,
        buffer,
        sparsity: None,
    };
    let (out_h, out_w) = (h.div_ceil(stride), w.div_ceil(stride));
    let model = TfliteModel {
        tensors: vec![
            tensor("x", vec![1, h, w, c_in], 0),
            tensor("kernel", kernel_shape, 1),
            tensor("bias", vec![c_out], 2),
            tensor("y", vec![1, out_h, out_w, c_out], 0),
        ],
        operators: vec![Operator {
            code: if depthwise {
                OpCode::DepthwiseConv2d
            } else {
                OpCode::Conv2d
            },
            inputs: vec![0, 1, 2],
            outputs: vec![3],
            options: OpOptions {
                padding: Padding::Same,
                stride: [stride, stride],
                ..OpOptions::default()
            },
            custom: None,
        }],
        inputs: vec![0],
        outputs: vec![3],
        buffers: vec![
            Vec::new(),
            random_bytes(rng, kernel_len),
            random_bytes(rng, c_out),
        ],
    };
    let mut net = Network::compile(&model, "bench").expect("a valid one-operator graph");
    for v in net.input_mut() {
        *v = rng.random_range(-1.0..1.0);
    }
    net
}

fn bench(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let cases = [
        (
            "conv2d_3x3_s2_192x192x3_to_16",
            [192, 192, 3],
            3,
            2,
            false,
            16,
        ),
        ("conv2d_1x1_48x48x32_to_64", [48, 48, 32], 1, 1, false, 64),
        (
            "conv2d_1x1_12x12x128_to_128",
            [12, 12, 128],
            1,
            1,
            false,
            128,
        ),
        ("depthwise_3x3_96x96x16", [96, 96, 16], 3, 1, true, 0),
        ("depthwise_3x3_s2_48x48x64", [48, 48, 64], 3, 2, true, 0),
    ];
    for (name, input, k, stride, depthwise, c_out) in cases {
        let mut net = one_conv(&mut rng, input, k, stride, depthwise, c_out);
        c.bench_function(name, |b| {
            b.iter(|| {
                net.run();
                std::hint::black_box(net.output(0).map(|(_, y)| y[0]))
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
