#!/usr/bin/env python3
"""Dev-only: writes OpenCV's SIFT output on a shared reference frame, the reference that
crates/keypoints/tests/opencv_parity.rs compares visage's SIFT with.

    target/dev-venv/bin/python scripts/dev/opencv_sift_reference.py
(the venv is the one scripts/dev/compare_sift.sh makes, with opencv-python-headless pinned.)

OpenCV's defaults (cv2.SIFT_create()), one thread, on the grey image (cv2 BGR→GRAY) of
../shared/reference/facemesh/d18_f100/frame.png. Positions as OpenCV reports them (a quarter
pixel right of and below the true ones, see docs/how-it-works.md).
"""
import json
import os

import cv2

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
IMAGE = os.path.join(ROOT, "..", "shared", "reference", "facemesh", "d18_f100", "frame.png")
OUT = os.path.join(ROOT, "crates", "keypoints", "tests", "data", "opencv_sift_d18_f100.json")


def main():
    cv2.setNumThreads(1)
    grey = cv2.cvtColor(cv2.imread(IMAGE, cv2.IMREAD_COLOR), cv2.COLOR_BGR2GRAY)
    kps, desc = cv2.SIFT_create().detectAndCompute(grey, None)
    record = {
        "generator": f"scripts/dev/opencv_sift_reference.py, OpenCV {cv2.__version__}",
        "image": "reference/facemesh/d18_f100/frame.png",
        "width": int(grey.shape[1]),
        "height": int(grey.shape[0]),
        "keypoints": [{"x": round(k.pt[0], 4), "y": round(k.pt[1], 4), "size": round(k.size, 4),
                       "angle": round(k.angle, 3), "response": round(k.response, 6),
                       "octave": int(k.octave)} for k in kps],
        "descriptors": [[int(v) for v in d] for d in desc],
    }
    with open(OUT, "w") as f:
        json.dump(record, f, separators=(",", ":"))
        f.write("\n")
    print(f"{OUT}: {len(kps)} keypoints")


if __name__ == "__main__":
    main()
