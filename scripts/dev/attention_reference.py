#!/usr/bin/env python3
"""Dev-only: writes what MediaPipe's attention face mesh (`face_landmark_with_attention.tflite`,
the network behind `refine_landmarks=True`) returns for the reference crops, the reference that
crates/face/tests/attention_parity.rs compares visage's attention network with.

    python3 -m venv target/dev-venv-mp
    target/dev-venv-mp/bin/pip install mediapipe==0.10.21 pillow
    target/dev-venv-mp/bin/python scripts/dev/attention_reference.py

The network runs inside MediaPipe's own `FaceLandmarkCpu` subgraph (side packet
`WITH_ATTENTION: true`; its three custom operators and its refinement of the 468 mesh points by
the lips, eyes and irises), given `../shared/reference/facemesh/CASE/crop192.png` as the image and
the whole image as the region of interest, so the network's input is that crop exactly. The same
subgraph without attention reproduces `landmarks_raw.json` (the plain mesh network on the same
crop) to 6e-5 px, which checks that the whole-image region adds no resampling.

Written per case: the 478 refined points × (x, y, z) in crop pixels (MediaPipe's normalised
coordinates × 192, the networks' own output units; z with the scale of x).
"""
import json
import os

import numpy as np
from PIL import Image
from google.protobuf import text_format
from mediapipe.framework import calculator_pb2
from mediapipe.framework.formats import rect_pb2
from mediapipe.python import solution_base

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
REFERENCE = os.path.join(ROOT, "..", "shared", "reference", "facemesh")
OUT = os.path.join(ROOT, "crates", "face", "tests", "data", "attention_reference.json")
SIDE = 192

GRAPH = """
input_stream: "image"
input_stream: "roi"
input_side_packet: "with_attention"
output_stream: "landmarks"
node {
  calculator: "FaceLandmarkCpu"
  input_stream: "IMAGE:image"
  input_stream: "ROI:roi"
  input_side_packet: "WITH_ATTENTION:with_attention"
  output_stream: "LANDMARKS:landmarks"
}
"""


def main():
    config = text_format.Parse(GRAPH, calculator_pb2.CalculatorGraphConfig())
    graph = solution_base.SolutionBase(
        graph_config=config, side_inputs={"with_attention": True}, outputs=["landmarks"])
    whole = rect_pb2.NormalizedRect(x_center=0.5, y_center=0.5, width=1.0, height=1.0, rotation=0.0)
    cases = [c["case"] for c in json.load(open(os.path.join(REFERENCE, "index.json")))]
    out = {
        "generator": "scripts/dev/attention_reference.py, mediapipe==0.10.21 (FaceLandmarkCpu, "
                     "WITH_ATTENTION, the whole crop as the region of interest)",
        "units": "crop pixels of crop192.png (MediaPipe normalised × 192); z with the scale of x",
        "cases": {},
    }
    for case in cases:
        crop = np.asarray(Image.open(os.path.join(REFERENCE, case, "crop192.png")).convert("RGB"))
        assert crop.shape == (SIDE, SIDE, 3), (case, crop.shape)
        landmarks = graph.process({"image": crop, "roi": whole}).landmarks
        points = [[round(p.x * SIDE, 5), round(p.y * SIDE, 5), round(p.z * SIDE, 5)]
                  for p in landmarks.landmark]
        assert len(points) == 478, (case, len(points))
        out["cases"][case] = points
    with open(OUT, "w") as f:
        json.dump(out, f, separators=(",", ":"))
        f.write("\n")
    print(f"wrote {OUT}: {len(cases)} cases")


if __name__ == "__main__":
    main()
