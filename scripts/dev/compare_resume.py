#!/usr/bin/env python3
"""Dev-only: how close a resumed run comes to an uninterrupted one (docs/performance.md,
"Resuming a run").

Runs `visage run CLIP` whole, and again stopped after N frames by `--max-frames N` then
continued with `--resume` (the limit raised: the run goes on after frame N-1 with its warm-up,
as after a kill), and compares the two folders' point caches and blendshape curves over the
frames after the resume point. Needs numpy (target/dev-venv from compare_sift.sh has it):

    target/dev-venv/bin/python scripts/dev/compare_resume.py CLIP [--frames 320] \
        [--bin target/release/visage] [--models models]
"""
import argparse
import json
import pathlib
import struct
import subprocess
import tempfile

import numpy as np


def point_cache(path):
    data = path.read_bytes()
    points, = struct.unpack("<i", data[16:20])
    samples, = struct.unpack("<i", data[28:32])
    return np.frombuffer(data[32:], dtype="<f4").reshape(samples, points, 3).astype(float)


def weights(path):
    return np.array([f["weights"] for f in json.loads(path.read_text())["frames"]])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("clip")
    parser.add_argument("--frames", type=int, default=320, help="frames before the resume")
    parser.add_argument("--bin", default="target/release/visage")
    parser.add_argument("--models", default="models")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        whole, part = pathlib.Path(tmp, "whole"), pathlib.Path(tmp, "part")
        run = [args.bin, "run", args.clip, "--quiet", "--models", args.models]
        subprocess.run(run + ["--out", str(whole)], check=True)
        subprocess.run(run + ["--out", str(part), "--max-frames", str(args.frames)], check=True)
        subprocess.run(run + ["--out", str(part), "--resume", "--max-frames", "1000000"],
                       check=True)
        resumed = json.loads((part / "metrics.json").read_text())["resumed"]
        after = resumed["after_frame"]
        a, b = point_cache(whole / "sequence.pc2"), point_cache(part / "sequence.pc2")
        assert a.shape == b.shape, (a.shape, b.shape)
        distance = np.linalg.norm(a - b, axis=2).mean(axis=1)[after + 1:] * 1000
        step = lambda x: np.linalg.norm(x[after + 1] - x[after], axis=1).mean() * 1000
        bs = np.abs(weights(whole / "blendshapes.json") - weights(part / "blendshapes.json"))
        print(f"resumed after frame {after}, warm-up {resumed['warm_up_frames']} frames, "
              f"{len(distance)} new frames")
        print(f"mean vertex distance to the uninterrupted run: first new frame "
              f"{distance[0]:.4f} mm, largest {distance.max():.4f} mm")
        print(f"step into the first new frame: {step(b):.3f} mm (uninterrupted {step(a):.3f})")
        print(f"largest blendshape weight difference: {bs[after + 1:].max():.3f}")


if __name__ == "__main__":
    main()
