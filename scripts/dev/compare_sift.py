#!/usr/bin/env python3
"""Dev-only: visage's SIFT against OpenCV's, by repeatability and matching score.

    scripts/dev/compare_sift.sh [--self-test] [--images A.png B.jpg ...] [--quick]

(the .sh makes a pinned venv in target/dev-venv and runs this file with it). Needs
`target/release/visage` (`cargo build --release`) unless --self-test, which puts OpenCV in
visage's place: its keypoints go through the same JSON file format and reader, so both columns
must agree exactly and OpenCV's numbers check the metrics (astronaut rotated 30°: repeatability
≈ 0.6–0.9, matching score ≈ 0.3–0.7).

Images: shared/data/images/astronaut.png, two video frames of shared/reference/facemesh, one
frame of each clip in shared/data/video (FFmpeg), and scikit-image's bundled samples (read from
the wheel's data folder, never downloaded). Each is converted to grey (cv2 BGR→GRAY) and both
detectors get that same grey image (visage as a grey PNG).

Transformations, each with the homography H mapping source pixels to transformed pixels (pixel
centres at integers, OpenCV's convention):
- rot30: rotation by 30° (counter-clockwise on screen) about the centre ((w−1)/2, (h−1)/2), the
  canvas enlarged to hold the whole image (black corners; cv2.warpAffine, bilinear).
- scale0.5: cv2.resize(fx=fy=0.5, INTER_AREA): x' = (x + 0.5)·0.5 − 0.5, same for y.
- contrast: I' = clip(round(0.7·I + 40), 0, 255); H = identity.

Definitions (after Mikolajczyk & Schmid 2005, simplified), ε = 2.5 px in the transformed image:
- Common area: source keypoints p with H·p inside the transformed image, transformed keypoints q
  with H⁻¹·q inside the source image (both rectangles [0, w−1]×[0, h−1], shrunk by --margin).
  n_s, n_t are the counts there.
- Repeatability: pairs (p, q) of the common area with |H·p − q| ≤ ε and sizes agreeing within a
  factor 1.5 after scaling (max(s·size_p/size_q, size_q/(s·size_p)) ≤ 1.5, s = √|det| of H's
  linear part) are matched one-to-one, greedily by distance; repeatability = pairs / min(n_s, n_t).
  (OpenCV duplicates a keypoint per extra orientation peak; one-to-one keeps the ratio ≤ 1.)
- Matching score: each source descriptor of the common area against the transformed ones
  (brute-force L2, two nearest neighbours, no cross-check), kept if d1 < 0.8·d2 (Lowe's ratio);
  correct if |H·p − q| ≤ ε (location only); matching score = correct / min(n_s, n_t).
- Time: detection and description of the source image, one thread, alternating --repeat rounds
  (default 5): one OpenCV detectAndCompute in this process, one `visage keypoints --repeat 3`
  whose printed median covers detection only (no start-up, PNG decode or JSON write); medians.
Keypoint counts in the table are totals per image (source/transformed), not the common area's.

Progress lines on stderr also give the "bias": the mean of q − H·p over the correct matches, in
transformed pixels. OpenCV reports positions 0.25 px right of and below the true ones (it doubles
the image centre-aligned, x₂ = 2x + 0.5, then halves keypoint positions, x₂/2 = x + 0.25), which
shows as (+0.13, +0.13) at scale0.5 and (−0.09, +0.16) at rot30: expected, well within ε.
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import cv2
import numpy as np

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
SHARED = os.path.normpath(os.path.join(ROOT, "..", "shared"))
EPS_PX = 2.5
SIZE_RATIO = 1.5
LOWE_RATIO = 0.8
REFERENCE_FRAMES = ["d13_f150", "d18_f100"]
VIDEO_FRAMES = [("lp_d13.mp4", 75), ("lp_d18.mp4", 50)]
SKIMAGE_SAMPLES = ["coffee.png", "chelsea.png", "rocket.jpg", "camera.png", "ihc.png"]


def grey(path):
    img = cv2.imread(path, cv2.IMREAD_COLOR)
    if img is None:
        sys.exit(f"compare_sift: cannot read {path}")
    return cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)


def default_images(tmp, quick):
    """(name, path) of the default image set; skips what is missing, with a note."""
    out = [("astronaut", os.path.join(SHARED, "data", "images", "astronaut.png"))]
    out += [(f"ref {c}", os.path.join(SHARED, "reference", "facemesh", c, "frame.png"))
            for c in REFERENCE_FRAMES]
    if shutil.which("ffmpeg") and not quick:
        for clip, n in VIDEO_FRAMES:
            src, dst = os.path.join(SHARED, "data", "video", clip), os.path.join(tmp, f"{clip}_{n}.png")
            if os.path.exists(src):
                subprocess.run(["ffmpeg", "-v", "error", "-y", "-i", src, "-vf",
                                f"select=eq(n\\,{n})", "-frames:v", "1", dst], check=True)
                out.append((f"{clip[:-4]} f{n}", dst))
    try:
        import skimage.data  # only for the folder of its bundled files
        folder = os.path.dirname(skimage.data.__file__)
        samples = SKIMAGE_SAMPLES[:2] if quick else SKIMAGE_SAMPLES
        out += [(f"skimage {f.split('.')[0]}", os.path.join(folder, f)) for f in samples]
    except ImportError:
        print("note: scikit-image missing, its sample images are skipped", file=sys.stderr)
    kept = [(n, p) for n, p in out if os.path.exists(p)]
    for n, p in out:
        if not os.path.exists(p):
            print(f"note: {p} missing, skipped", file=sys.stderr)
    return kept


# --- transformations: (name, image, H source → transformed) ---------------------------------

def rotate(img, degrees):
    h, w = img.shape
    m = cv2.getRotationMatrix2D(((w - 1) / 2, (h - 1) / 2), degrees, 1.0)
    c, s = abs(m[0, 0]), abs(m[0, 1])
    nw, nh = int(np.ceil(w * c + h * s)), int(np.ceil(w * s + h * c))
    m[:, 2] += [(nw - 1) / 2 - (w - 1) / 2, (nh - 1) / 2 - (h - 1) / 2]
    out = cv2.warpAffine(img, m, (nw, nh), flags=cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    return out, np.vstack([m, [0, 0, 1]])


def half(img):
    f = 0.5  # fx given (no dsize) → OpenCV maps with exactly this factor, size rounded
    out = cv2.resize(img, None, fx=f, fy=f, interpolation=cv2.INTER_AREA)
    b = 0.5 * f - 0.5
    return out, np.array([[f, 0, b], [0, f, b], [0, 0, 1]])


def contrast(img):
    out = np.clip(np.rint(0.7 * img.astype(np.float64) + 40), 0, 255).astype(np.uint8)
    return out, np.eye(3)


TRANSFORMS = [("rot30", lambda i: rotate(i, 30.0)), ("scale0.5", half), ("contrast", contrast)]


# --- features: the JSON format visage writes, and its reader ---------------------------------

def write_features(path, img, kps, desc):
    """OpenCV's keypoints in visage's `keypoints --out` format."""
    h, w = img.shape
    desc = np.zeros((0, 128), np.uint8) if desc is None else desc
    doc = {"width": w, "height": h,
           "keypoints": [{"x": k.pt[0], "y": k.pt[1], "size": k.size, "angle": k.angle,
                          "response": k.response, "octave": k.octave} for k in kps],
           "descriptors": np.rint(desc).astype(int).tolist()}
    with open(path, "w") as f:
        json.dump(doc, f)


def read_features(path, img):
    """{xy (n×2), size (n), desc (n×128 float32)} from a `keypoints --out` file, checked."""
    with open(path) as f:
        doc = json.load(f)
    h, w = img.shape
    if (doc["width"], doc["height"]) != (w, h):
        sys.exit(f"compare_sift: {path} is {doc['width']}×{doc['height']}, image is {w}×{h}")
    kps = doc["keypoints"]
    desc = np.array(doc["descriptors"], np.float64).reshape(-1, 128)
    if len(desc) != len(kps) or (len(desc) and (desc.min() < 0 or desc.max() > 255)):
        sys.exit(f"compare_sift: {path}: {len(kps)} keypoints, {len(desc)} descriptors, "
                 "or a descriptor value outside 0–255")
    return {"xy": np.array([[k["x"], k["y"]] for k in kps], np.float64).reshape(-1, 2),
            "size": np.array([k["size"] for k in kps], np.float64),
            "desc": desc.astype(np.float32)}


def from_cv(kps, desc):
    return {"xy": np.array([k.pt for k in kps], np.float64).reshape(-1, 2),
            "size": np.array([k.size for k in kps], np.float64),
            "desc": (np.zeros((0, 128)) if desc is None else desc).astype(np.float32)}


def opencv(img):
    """Keypoints, descriptors and the wall time (s) of one detectAndCompute call."""
    sift = cv2.SIFT_create()
    t = time.perf_counter()
    kps, desc = sift.detectAndCompute(img, None)
    return kps, desc, time.perf_counter() - t


class Visage:
    """Runs `visage keypoints` on a grey PNG; or, with self_test, OpenCV through the JSON."""

    def __init__(self, binary, tmp, self_test):
        self.binary, self.tmp, self.self_test, self.n = binary, tmp, self_test, 0

    def features(self, img, repeat=1):
        """Features and the detection time (s): visage's own figure for the detection (in
        process, without start-up, PNG decode and JSON write; the median of `repeat` calls on the
        same buffers), or OpenCV's in self-test."""
        self.n += 1
        png, out = (os.path.join(self.tmp, f"v{self.n}.{e}") for e in ("png", "json"))
        cv2.imwrite(png, img)
        if self.self_test:
            kps, desc, seconds = opencv(img)
            write_features(out, img, kps, desc)
        else:
            r = subprocess.run([self.binary, "keypoints", png, "--out", out,
                                "--repeat", str(repeat)],
                               cwd=ROOT, capture_output=True, text=True)
            if r.returncode != 0:
                sys.exit(f"compare_sift: {self.binary} keypoints {png} failed "
                         f"({r.returncode}):\n{r.stderr}")
            seconds = json.loads(r.stdout)["ms"] / 1e3
        return read_features(out, img), seconds


def alternate_timing(vis, img, rounds):
    """Median detection times (s) of OpenCV and visage, alternating: per round one OpenCV call
    (in this process, so its allocations are recycled as in a video loop) and one visage
    process whose figure is the median of 3 calls on the same buffers (the first allocates)."""
    tc, tv = [], []
    for _ in range(rounds):
        tc.append(opencv(img)[2])
        tv.append(vis.features(img, repeat=3)[1])
    return statistics.median(tc), statistics.median(tv)


# --- metrics ---------------------------------------------------------------------------------

def apply_h(h, xy):
    p = np.hstack([xy, np.ones((len(xy), 1))]) @ h.T
    return p[:, :2] / p[:, 2:3]


def inside(xy, shape, margin):
    h, w = shape
    return ((xy[:, 0] >= margin) & (xy[:, 0] <= w - 1 - margin)
            & (xy[:, 1] >= margin) & (xy[:, 1] <= h - 1 - margin))


def evaluate(src, tgt, h, src_shape, tgt_shape, margin):
    """(repeatability, matching score, mean q − H·p of the correct matches) src → tgt."""
    s_in = inside(apply_h(h, src["xy"]), tgt_shape, margin)
    t_in = inside(apply_h(np.linalg.inv(h), tgt["xy"]), src_shape, margin)
    p, q = apply_h(h, src["xy"][s_in]), tgt["xy"][t_in]
    denom = min(len(p), len(q))
    if denom == 0:
        return 0.0, 0.0, np.zeros(2)
    scale = np.sqrt(abs(np.linalg.det(h[:2, :2])))
    sp, sq = src["size"][s_in] * scale, tgt["size"][t_in]
    # Repeatability: candidate pairs within ε (cv2's brute-force radius search on 2-D points).
    bf = cv2.BFMatcher(cv2.NORM_L2)
    near = bf.radiusMatch(p.astype(np.float32), q.astype(np.float32), maxDistance=EPS_PX)
    pairs = sorted((m.distance, m.queryIdx, m.trainIdx) for ms in near for m in ms
                   if max(sp[m.queryIdx] / sq[m.trainIdx], sq[m.trainIdx] / sp[m.queryIdx])
                   <= SIZE_RATIO)
    used_p, used_q = set(), set()
    for _, i, j in pairs:
        if i not in used_p and j not in used_q:
            used_p.add(i)
            used_q.add(j)
    # Matching score: Lowe's ratio test on descriptors, correct by location.
    residuals = []
    if len(q) >= 2:
        for m in bf.knnMatch(src["desc"][s_in], tgt["desc"][t_in], k=2):
            if len(m) == 2 and m[0].distance < LOWE_RATIO * m[1].distance:
                r = q[m[0].trainIdx] - p[m[0].queryIdx]
                if np.hypot(*r) <= EPS_PX:
                    residuals.append(r)
    bias = np.mean(residuals, axis=0) if residuals else np.zeros(2)
    return len(used_p) / denom, len(residuals) / denom, bias


# --- main ------------------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--self-test", action="store_true",
                    help="OpenCV in visage's place, through the JSON format and reader")
    ap.add_argument("--bin", default=os.path.join(ROOT, "target", "release", "visage"))
    ap.add_argument("--images", nargs="+", help="image files instead of the default set")
    ap.add_argument("--quick", action="store_true", help="fewer images (no video, 2 samples)")
    ap.add_argument("--margin", type=float, default=0.0,
                    help="px the common area keeps away from the image borders (default 0)")
    ap.add_argument("--repeat", type=int, default=5, help="timed calls of each per image")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    if not args.self_test and not os.access(args.bin, os.X_OK):
        sys.exit(f"compare_sift: {args.bin} not found: `cargo build --release` (or --self-test)")
    other = "cv2 via JSON" if args.self_test else "visage"
    rows, timing = [], []
    with tempfile.TemporaryDirectory() as tmp:
        images = ([(os.path.basename(p), p) for p in args.images] if args.images
                  else default_images(tmp, args.quick))
        vis = Visage(args.bin, tmp, args.self_test)
        for name, path in images:
            img = grey(path)
            kc, dc, _ = opencv(img)
            c_src = from_cv(kc, dc)
            v_src, _ = vis.features(img)
            tc, tv = alternate_timing(vis, img, args.repeat)
            timing.append((name, img.shape, len(c_src["xy"]), tc, len(v_src["xy"]), tv))
            for tname, fn in TRANSFORMS:
                out, h = fn(img)
                c_tgt = from_cv(*opencv(out)[:2])
                v_tgt, _ = vis.features(out)
                rc, mc, bc = evaluate(c_src, c_tgt, h, img.shape, out.shape, args.margin)
                rv, mv, bv = evaluate(v_src, v_tgt, h, img.shape, out.shape, args.margin)
                rows.append((name, tname, f"{len(c_src['xy'])}/{len(c_tgt['xy'])}",
                             f"{len(v_src['xy'])}/{len(v_tgt['xy'])}", rc, rv, mc, mv))
                print(f"  {name} {tname}: rep {rc:.3f}/{rv:.3f}, match {mc:.3f}/{mv:.3f}, "
                      f"bias px ({bc[0]:+.2f}, {bc[1]:+.2f})/({bv[0]:+.2f}, {bv[1]:+.2f})",
                      file=sys.stderr)
    print(f"\nSIFT: OpenCV {cv2.__version__} (defaults, 1 thread) against {other}; "
          f"ε = {EPS_PX} px, size ratio ≤ {SIZE_RATIO}, Lowe ratio {LOWE_RATIO}, "
          f"margin {args.margin} px. Δ = {other} − OpenCV, percentage points.\n")
    print(f"| image | transform | kps OpenCV (src/tgt) | kps {other} | rep OpenCV | rep {other} "
          f"| Δ rep pp | match OpenCV | match {other} | Δ match pp |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, tname, kc, kv, rc, rv, mc, mv in rows:
        print(f"| {name} | {tname} | {kc} | {kv} | {rc:.3f} | {rv:.3f} | {100 * (rv - rc):+.1f} "
              f"| {mc:.3f} | {mv:.3f} | {100 * (mv - mc):+.1f} |")
    if rows:
        a = np.mean([r[4:] for r in rows], axis=0)
        print(f"| **average** | {len(rows)} cases | | | {a[0]:.3f} | {a[1]:.3f} "
              f"| {100 * (a[1] - a[0]):+.1f} | {a[2]:.3f} | {a[3]:.3f} | {100 * (a[3] - a[2]):+.1f} |")
    print(f"\nDetection and description time, one thread, alternating, median of {args.repeat} "
          f"rounds (visage: its own figure, the median of 3 calls on the same buffers).\n")
    print(f"| image | size | kps OpenCV | OpenCV ms | kps {other} | {other} ms | ratio |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for name, (hh, ww), nc, tc, nv, tv in timing:
        print(f"| {name} | {ww}×{hh} | {nc} | {1e3 * tc:.0f} | {nv} | {1e3 * tv:.0f} "
              f"| {tv / tc:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
