#!/usr/bin/env python3
"""How much of the tracked face's frame-to-frame non-rigid motion is noise.

Usage: scripts/landmark_motion.py OUT/landmarks.json   (from `visage run` or `visage landmarks`)

Each frame pair's 2-D similarity (rotation, scale, translation) is removed by least squares; of
the remaining landmark motion, the RMS first difference D1 and second difference D2 are
compared. White noise of σ per coordinate gives D1 = 2σ, D2 = √12·σ (ratio 1.73); smooth
motion gives D2 ≪ D1. Read as smooth motion + white noise, σ = D2/√12 and the noise's share of
the frame-to-frame variance is 4σ²/D1², which bounds what any denoiser can remove: jitter falls
at most by 1/√(1 − share). Pure Python (2-D similarities as complex numbers).
"""
import json
import math
import sys


def align(a, b):
    """b mapped onto a by the least-squares 2-D similarity (complex points)."""
    ca, cb = sum(a) / len(a), sum(b) / len(b)
    s = sum((q - cb).conjugate() * (p - ca) for p, q in zip(a, b))
    s /= sum(abs(q - cb) ** 2 for q in b)
    return [s * (q - cb) + ca for q in b]


def rms(points):
    return math.sqrt(sum(abs(p) ** 2 for p in points) / len(points))


frames = json.load(open(sys.argv[1]))["frames"]
tracks = [[complex(x, y) for x, y, _ in f["faces"][0]["landmarks"]] for f in frames if f["faces"]]
d1 = [rms([p - q for p, q in zip(tracks[k], align(tracks[k], tracks[k - 1]))]) for k in range(1, len(tracks))]
d2 = []
for k in range(2, len(tracks)):
    one, two = align(tracks[k], tracks[k - 1]), align(tracks[k], tracks[k - 2])
    d2.append(rms([p - 2 * q + r for p, q, r in zip(tracks[k], one, two)]))
d1, d2 = sum(d1) / len(d1), sum(d2) / len(d2)
share = min(1.0, (4 * d2 * d2 / 12) / (d1 * d1))
bound = 1 / math.sqrt(1 - share) if share < 1 else float("inf")
print(f"{sys.argv[1]}: {len(tracks)} frames; non-rigid landmark motion D1 {d1:.3f} px, "
      f"D2 {d2:.3f} px, D2/D1 {d2 / d1:.2f} (white noise 1.73); noise share {100 * share:.0f} %; "
      f"perfect denoising cuts jitter by at most {bound:.2f}x")
