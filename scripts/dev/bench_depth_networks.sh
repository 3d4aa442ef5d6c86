#!/usr/bin/env bash
# Times the depth networks: regenerates the test networks (checking they match the committed
# ones), makes a 256×256 U-Net of realistic size (7.8 M parameters, seeded weights), times it
# in ONNX Runtime (1 thread) for comparison, and runs visage-depth's criterion bench on both.
# Needs Python 3 with pip (a pinned virtual environment is made under target/).
set -euo pipefail
cd "$(dirname "$0")/../.."
venv=target/depth-networks-venv
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q onnx==1.23.2 numpy==2.4.6 onnxruntime==1.31.1
fi
data=crates/depth/tests/data
tmp=$(mktemp -d)
"$venv/bin/python" "$data/make_networks.py" "$tmp"
for f in "$tmp"/*.onnx; do
  cmp -s "$f" "$data/$(basename "$f")" || echo "bench: $(basename "$f") differs from the committed one" >&2
done
unet=target/unet256.onnx
[ -f "$unet" ] || "$venv/bin/python" "$data/make_networks.py" --unet "$unet"
"$venv/bin/python" - "$unet" "$data/inverse_depth.onnx" <<'PY'
import sys, time
import numpy as np, onnxruntime as ort
for path in sys.argv[1:]:
    so = ort.SessionOptions(); so.intra_op_num_threads = 1
    s = ort.InferenceSession(path, so)
    i = s.get_inputs()[0]
    x = np.random.default_rng(0).random(i.shape).astype(np.float32)
    for _ in range(3): s.run(None, {i.name: x})
    t = []
    for _ in range(10):
        a = time.perf_counter(); s.run(None, {i.name: x}); t.append(time.perf_counter() - a)
    print(f"onnxruntime 1 thread {path}: median {1e3 * sorted(t)[5]:.2f} ms")
PY
VISAGE_UNET="$PWD/$unet" cargo bench -p visage-depth --bench depth_network
