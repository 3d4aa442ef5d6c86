#!/usr/bin/env python3
"""Dev-only: writes what MediaPipe's full-range face detector finds on a few test images, the
reference that crates/face/tests/full_range_parity.rs compares visage's full-range detector with.

    python3 -m venv target/dev-venv-mp
    target/dev-venv-mp/bin/pip install mediapipe==0.10.21 ai-edge-litert
    target/dev-venv-mp/bin/python scripts/dev/full_range_reference.py

Detections: MediaPipe's own solution, `mp.solutions.face_detection.FaceDetection(model_selection=1,
min_detection_confidence=0.6)` (the `face_detection_full_range_cpu` graph: letter-box to 192×192,
2304 anchors, score ≥ 0.6, weighted NMS), boxes and keypoints in image pixels (MediaPipe's
normalised coordinates × the image size).

MediaPipe finds faces down to about 70 px wide on a whole 1280×720 frame (a face then covers ~10
of the network's 192 input pixels); smaller faces need the frame cut into tiles. For the cases
with a `tile` side, the detections of MediaPipe on each tile (a crop of the image, placed as
`tiles()` places them; visage's `FaceDetector::tiles` must place them the same way) are written too.

The test images are built from ../shared so that the Rust test can rebuild them bit for bit: the
portrait ../shared/data/images/astronaut.png (its face is about 94 px wide) shrunk by an exact
integer area average (`area_resize`, factor num/den) and pasted on a 1280×720 grey (128) canvas,
and a video frame as decoded in ../shared/reference/facemesh. The recipe of each case is in the
JSON next to its detections.

Raw outputs: the network alone (`face_detection_full_range_sparse.tflite` from the same wheel,
run by ai-edge-litert's TFLite interpreter) on one fixed input, the portrait area-resized by 3/8 to
exactly 192×192, RGB scaled to [−1, 1]: the 6 highest-scoring anchors with their 16 regressors,
and every 32nd classificator logit.
"""
import json
import os

import cv2
import numpy as np

import mediapipe as mp

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
SHARED = os.path.join(ROOT, "..", "shared")
OUT = os.path.join(ROOT, "crates", "face", "tests", "data", "full_range_reference.json")
MODEL = os.path.join(os.path.dirname(mp.__file__), "modules", "face_detection",
                     "face_detection_full_range_sparse.tflite")

CANVAS = (1280, 720)
GREY = 128
PORTRAIT = "data/images/astronaut.png"

# name, recipe: ("canvas", [num, den], [[x, y], …]) pastes the shrunk portrait at each (x, y)
# (top-left corner); ("frame", path) is an image of ../shared as it is.
# A case with "tile": T is also cut into T×T tiles.
CASES = [
    ("two_faces_82px", {"kind": "canvas", "scale": [7, 8], "paste": [[40, 150], [760, 100]]}),
    ("one_face_70px", {"kind": "canvas", "scale": [3, 4], "paste": [[500, 200]]}),
    ("one_face_59px", {"kind": "canvas", "scale": [5, 8], "paste": [[200, 300]]}),
    ("one_face_41px", {"kind": "canvas", "scale": [7, 16], "paste": [[900, 80]], "tile": 640}),
    ("empty_canvas", {"kind": "canvas", "scale": [1, 1], "paste": []}),
    ("d13_f150_frame", {"kind": "frame", "path": "reference/facemesh/d13_f150/frame.png"}),
]


def axis_tiles(length, tile):
    """Tile origins along one axis: one tile if it fits, else the fewest tiles overlapping by at
    least a quarter tile, spread evenly (integer floor)."""
    if length <= tile:
        return [(0, length)]
    step = tile - tile // 4
    n = -(-(length - tile) // step) + 1
    return [(i * (length - tile) // (n - 1), tile) for i in range(n)]


def tiles(width, height, tile):
    """[x, y, w, h] of each tile, row by row."""
    return [[x, y, w, h] for y, h in axis_tiles(height, tile) for x, w in axis_tiles(width, tile)]


def read_rgb(rel):
    bgr = cv2.imread(os.path.join(SHARED, rel), cv2.IMREAD_COLOR)
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def area_weights(n_in, num, den):
    """Integer overlap of input pixel i (scaled to [i·num, (i+1)·num)) with output pixel o
    ([o·den, (o+1)·den)); each output row of weights sums to den."""
    n_out = n_in * num // den
    w = np.zeros((n_out, n_in), np.int64)
    for o in range(n_out):
        a, b = o * den, (o + 1) * den
        for i in range(a // num, min((b + num - 1) // num, n_in)):
            w[o, i] = max(0, min(b, (i + 1) * num) - max(a, i * num))
    return w


def area_resize(img, num, den):
    """Exact area-average resize by num/den in integers, rounded half up."""
    wy = area_weights(img.shape[0], num, den)
    wx = area_weights(img.shape[1], num, den)
    img = img.astype(np.int64)
    acc = np.stack([wy @ img[:, :, c] @ wx.T for c in range(img.shape[2])], axis=2)
    d2 = den * den
    return ((acc + d2 // 2) // d2).astype(np.uint8)


def build(recipe):
    if recipe["kind"] == "frame":
        return read_rgb(recipe["path"])
    canvas = np.full((CANVAS[1], CANVAS[0], 3), GREY, np.uint8)
    small = area_resize(read_rgb(PORTRAIT), *recipe["scale"])
    for x, y in recipe["paste"]:
        canvas[y:y + small.shape[0], x:x + small.shape[1]] = small
    return canvas


def detections(detector, rgb):
    h, w = rgb.shape[:2]
    out = []
    for d in detector.process(rgb).detections or []:
        b = d.location_data.relative_bounding_box
        out.append({
            "score": round(float(d.score[0]), 5),
            "box": [round(v, 3) for v in (b.xmin * w, b.ymin * h, b.width * w, b.height * h)],
            "keypoints": [[round(k.x * w, 3), round(k.y * h, 3)]
                          for k in d.location_data.relative_keypoints],
        })
    return out


def raw_outputs():
    from ai_edge_litert.interpreter import Interpreter
    import ai_edge_litert

    rgb = area_resize(read_rgb(PORTRAIT), 3, 8)
    assert rgb.shape == (192, 192, 3)
    x = (rgb.astype(np.float32) / np.float32(127.5) - np.float32(1.0))[None]
    interp = Interpreter(model_path=MODEL, num_threads=1)
    interp.allocate_tensors()
    interp.set_tensor(interp.get_input_details()[0]["index"], x)
    interp.invoke()
    outs = {o["name"]: interp.get_tensor(o["index"]) for o in interp.get_output_details()}
    reg = outs["Identity"].reshape(2304, 16)
    cls = outs["Identity_1"].reshape(2304)
    top = np.argsort(-cls)[:6]
    return {
        "runtime": f"ai-edge-litert {getattr(ai_edge_litert, '__version__', '?')} "
                   "TFLite interpreter, 1 thread",
        "input": "astronaut.png area-resized by 3/8 to 192x192, RGB/127.5 - 1",
        "top_anchors": [{"anchor": int(i), "logit": round(float(cls[i]), 5),
                         "regressors": [round(float(v), 5) for v in reg[i]]} for i in top],
        "logits_every_32nd": [round(float(v), 4) for v in cls[::32]],
    }


def main():
    record = {
        "generator": "scripts/dev/full_range_reference.py, mediapipe "
                     f"{mp.__version__} solutions.face_detection(model_selection=1, "
                     "min_detection_confidence=0.6)",
        "canvas": {"size": list(CANVAS), "grey": GREY, "portrait": PORTRAIT},
        "cases": [],
    }
    with mp.solutions.face_detection.FaceDetection(
            model_selection=1, min_detection_confidence=0.6) as detector:
        for name, recipe in CASES:
            rgb = build(recipe)
            dets = detections(detector, rgb)
            case = {"name": name, **recipe, "size": [int(rgb.shape[1]), int(rgb.shape[0])],
                    "detections": dets}
            print(f"{name}: {len(dets)} face(s) " +
                  ", ".join(f"{d['box'][2]:.1f} px wide, score {d['score']:.3f}" for d in dets))
            if "tile" in recipe:
                case["tiles"] = []
                for x, y, w, h in tiles(rgb.shape[1], rgb.shape[0], recipe["tile"]):
                    crop = np.ascontiguousarray(rgb[y:y + h, x:x + w])
                    tile_dets = detections(detector, crop)
                    case["tiles"].append({"rect": [x, y, w, h], "detections": tile_dets})
                    print(f"  tile {x},{y} {w}x{h}: {len(tile_dets)} face(s) " +
                          ", ".join(f"{d['box'][2]:.1f} px, {d['score']:.3f}" for d in tile_dets))
            record["cases"].append(case)
    record["raw"] = raw_outputs()
    os.makedirs(os.path.dirname(OUT), exist_ok=True)
    with open(OUT, "w") as f:
        # One line per case, compact inside.
        head = {k: v for k, v in record.items() if k not in ("cases", "raw")}
        f.write(json.dumps(head, separators=(",", ":"))[:-1] + ',\n"cases":[\n')
        f.write(",\n".join(json.dumps(c, separators=(",", ":")) for c in record["cases"]))
        f.write('],\n"raw":' + json.dumps(record["raw"], separators=(",", ":")) + "}\n")
    print(f"{OUT}: {os.path.getsize(OUT)} bytes")


if __name__ == "__main__":
    main()
