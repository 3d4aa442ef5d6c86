#!/usr/bin/env python3
"""Writes the ONNX depth networks of visage-depth's tests (and, on request, a U-Net of realistic
size for timing).

    python3 make_networks.py OUT_DIR            the test networks (committed beside this script)
    python3 make_networks.py --unet OUT.onnx    a 256×256 U-Net with seeded random weights

Needs the PyPI packages onnx==1.23.2 and numpy (`scripts/dev/make_depth_networks.sh` sets up a
pinned virtual environment and runs this). Every file passes `onnx.checker.check_model`.

The test network, `inverse_depth.onnx` with `inverse_depth.json`: input `image`, 1×3×64×64,
normalised as the common depth networks expect (RGB in [0, 1], ImageNet mean and standard
deviation); output `depth`, 1×1×32×32, a relative inverse depth:

    depth[i, j] = 0.2 + 0.6 · (mean red value in [0, 1] of the 2×2 input block (2i.., 2j..))

It is built like a small U-Net — a 1×1 convolution that undoes the normalisation, ReLU, 2×2
average pooling, a 3×3 convolution (identity kernel, zero padding), a concatenation of both
paths and a 1×1 convolution that merges them — so a colour image whose red channel is constant
over 2×2 blocks gives a depth known exactly.

The networks that must be refused, each with the error the tests expect:
- `rank3_input.onnx`: its input has rank 3 (3×64×64: no batch axis);
- `unsupported_op.onnx`: a MaxUnpool node, which the ONNX runtime visage uses does not implement;
- `wrong_output.onnx`: a 64×64 input gives a 16×48 output (the aspect ratio differs).
"""
import sys

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

OPSET = 17
MEAN = [0.485, 0.456, 0.406]
STD = [0.229, 0.224, 0.225]


def model(nodes, inputs, outputs, initializers, name):
    graph = helper.make_graph(nodes, name, inputs, outputs, initializer=initializers)
    m = helper.make_model(graph, opset_imports=[helper.make_opsetid("", OPSET)],
                          producer_name="visage make_networks.py")
    m.ir_version = 8
    onnx.checker.check_model(m, full_check=True)
    return m


def tensor(name, array):
    return numpy_helper.from_array(np.asarray(array, dtype=np.float32), name)


def image_input(shape=(1, 3, 64, 64)):
    return helper.make_tensor_value_info("image", TensorProto.FLOAT, list(shape))


def depth_output(shape):
    return helper.make_tensor_value_info("depth", TensorProto.FLOAT, list(shape))


def inverse_depth():
    # r = x_R · std_R + mean_R: the red value in [0, 1].
    denorm_w = np.zeros((1, 3, 1, 1), np.float32)
    denorm_w[0, 0, 0, 0] = STD[0]
    identity3 = np.zeros((1, 1, 3, 3), np.float32)
    identity3[0, 0, 1, 1] = 1.0
    # Both paths carry the block mean; the merge takes half of each, then 0.2 + 0.6 · r.
    merge_w = np.full((1, 2, 1, 1), 0.5 * 0.6, np.float32)
    nodes = [
        helper.make_node("Conv", ["image", "denorm_w", "denorm_b"], ["red"], name="denormalise"),
        helper.make_node("Relu", ["red"], ["red_pos"], name="relu"),
        helper.make_node("AveragePool", ["red_pos"], ["pooled"], kernel_shape=[2, 2],
                         strides=[2, 2], name="down"),
        helper.make_node("Conv", ["pooled", "identity_w", "zero_b"], ["refined"],
                         pads=[1, 1, 1, 1], name="conv3x3"),
        helper.make_node("Concat", ["pooled", "refined"], ["skip"], axis=1, name="skip"),
        helper.make_node("Conv", ["skip", "merge_w", "merge_b"], ["depth"], name="merge"),
    ]
    inits = [
        tensor("denorm_w", denorm_w),
        tensor("denorm_b", [MEAN[0]]),
        tensor("identity_w", identity3),
        tensor("zero_b", [0.0]),
        tensor("merge_w", merge_w),
        tensor("merge_b", [0.2]),
    ]
    return model(nodes, [image_input()], [depth_output((1, 1, 32, 32))], inits, "inverse_depth")


def rank3_input():
    nodes = [helper.make_node("ReduceMean", ["image"], ["depth"], axes=[0], keepdims=1,
                              name="mean")]
    return model(nodes, [image_input((3, 64, 64))], [depth_output((1, 64, 64))], [],
                 "rank3_input")


def unsupported_op():
    nodes = [
        helper.make_node("MaxPool", ["image"], ["pooled", "indices"], kernel_shape=[2, 2],
                         strides=[2, 2], name="pool"),
        helper.make_node("MaxUnpool", ["pooled", "indices"], ["unpooled"], kernel_shape=[2, 2],
                         strides=[2, 2], name="unpool"),
        helper.make_node("ReduceMean", ["unpooled"], ["depth"], axes=[1], keepdims=1,
                         name="mean"),
    ]
    return model(nodes, [image_input()], [depth_output((1, 1, 64, 64))], [],
                 "unsupported_op")


def wrong_output():
    # The channel mean, as a depth head would give it, resized to the wrong aspect ratio.
    nodes = [
        helper.make_node("ReduceMean", ["image"], ["mean"], axes=[1], keepdims=1, name="mean"),
        helper.make_node("Resize", ["mean", "", "", "sizes"], ["depth"], mode="linear",
                         name="resize"),
    ]
    inits = [numpy_helper.from_array(np.array([1, 1, 16, 48], np.int64), "sizes")]
    return model(nodes, [image_input()], [depth_output((1, 1, 16, 48))], inits,
                 "wrong_output")


def unet(size=256, base=32, levels=4, seed=0):
    """A U-Net: `levels` encoder stages (two 3×3 convolutions + ReLU each, 2×2 max pooling
    between), a bottleneck, decoder stages (bilinear ×2 upsampling, concatenation with the
    encoder's features, two 3×3 convolutions), a 1×1 convolution to one channel and a sigmoid
    (an inverse depth in (0, 1)). Channels base·2^l. He-initialised seeded weights."""
    rng = np.random.default_rng(seed)
    nodes, inits = [], []
    counter = [0]

    def conv(x, cin, cout, k=3, relu=True):
        counter[0] += 1
        n = counter[0]
        w = rng.standard_normal((cout, cin, k, k)).astype(np.float32) * np.sqrt(2.0 / (cin * k * k))
        inits.append(tensor(f"w{n}", w))
        inits.append(tensor(f"b{n}", np.zeros(cout, np.float32)))
        pad = k // 2
        nodes.append(helper.make_node("Conv", [x, f"w{n}", f"b{n}"], [f"c{n}"],
                                      pads=[pad] * 4, name=f"conv{n}"))
        if not relu:
            return f"c{n}"
        nodes.append(helper.make_node("Relu", [f"c{n}"], [f"r{n}"], name=f"relu{n}"))
        return f"r{n}"

    x, cin = "image", 3
    skips = []
    for level in range(levels):
        c = base * 2 ** level
        x = conv(conv(x, cin, c), c, c)
        skips.append((x, c))
        nodes.append(helper.make_node("MaxPool", [x], [f"p{level}"], kernel_shape=[2, 2],
                                      strides=[2, 2], name=f"pool{level}"))
        x, cin = f"p{level}", c
    c = base * 2 ** levels
    x = conv(conv(x, cin, c), c, c)
    cin = c
    inits.append(numpy_helper.from_array(np.array([1, 1, 2, 2], np.float32), "up_scales"))
    for level in reversed(range(levels)):
        skip, c = skips[level]
        nodes.append(helper.make_node("Resize", [x, "", "up_scales"], [f"u{level}"],
                                      mode="linear", name=f"up{level}"))
        nodes.append(helper.make_node("Concat", [f"u{level}", skip], [f"cat{level}"], axis=1,
                                      name=f"cat{level}"))
        x = conv(conv(f"cat{level}", cin + c, c), c, c)
        cin = c
    x = conv(x, cin, 1, k=1, relu=False)
    nodes.append(helper.make_node("Sigmoid", [x], ["depth"], name="sigmoid"))
    return model(nodes, [image_input((1, 3, size, size))],
                 [depth_output((1, 1, size, size))], inits, "unet")


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--unet":
        onnx.save(unet(), sys.argv[2])
        return
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    for name, make in [("inverse_depth", inverse_depth), ("rank3_input", rank3_input),
                       ("unsupported_op", unsupported_op), ("wrong_output", wrong_output)]:
        onnx.save(make(), f"{out}/{name}.onnx")


if __name__ == "__main__":
    main()
