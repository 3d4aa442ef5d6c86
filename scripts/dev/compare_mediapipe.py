"""Side by side: MediaPipe FaceMesh (Python, landmarks only, XNNPACK) against `visage bench`
(landmarks, metric face fit, fusion, quality figures) on the same clips, alternated.

    python compare_mediapipe.py VISAGE_BINARY CLIP... [--pairs N] [--refine]

`--refine` runs FaceMesh with `refine_landmarks=True` (its attention model: 478 landmarks with
the irises), the nearest MediaPipe comes to visage's landmarks and irises.

Run through scripts/dev/compare_mediapipe.sh, which makes the pinned environment. For each clip
and pair it runs MediaPipe, then visage, and prints per run:
- fps inside each tool's loop (start-up excluded; both include decoding: OpenCV in MediaPipe's
  process, FFmpeg in visage's child process);
- CPU ms per frame of the whole process tree, decoder included: for MediaPipe the loop's CPU
  time in its own process (OpenCV decodes in-process), for visage the CPU time of `visage bench`
  and its FFmpeg child over the whole process, start-up included, so it is an upper bound;
- peak RSS of each tool's own process (MediaPipe: its Python process; visage: as `visage bench`
  reports it, without FFmpeg's).
Then the medians and the ratio visage / MediaPipe per clip.
"""

import json
import resource
import statistics
import subprocess
import sys
import time


def mediapipe_run(clip, refine):
    """Runs FaceMesh over every frame of `clip` in a fresh process; returns its figures."""
    code = r"""
import json, resource, sys, time
import cv2, mediapipe as mp
mesh = mp.solutions.face_mesh.FaceMesh(static_image_mode=False, max_num_faces=1,
                                       refine_landmarks=sys.argv[2] == "refine")
cap = cv2.VideoCapture(sys.argv[1])
ok, frame = cap.read()
mesh.process(cv2.cvtColor(frame, cv2.COLOR_BGR2RGB))  # start-up: graph and first inference
frames, found = 0, 0
r0, t0 = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
while True:
    ok, frame = cap.read()
    if not ok:
        break
    result = mesh.process(cv2.cvtColor(frame, cv2.COLOR_BGR2RGB))
    frames += 1
    found += result.multi_face_landmarks is not None
wall = time.perf_counter() - t0
r1 = resource.getrusage(resource.RUSAGE_SELF)
cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
print(json.dumps({"frames": frames, "found": found, "fps": frames / wall,
                  "cpu_ms": 1e3 * cpu / frames, "rss_mib": r1.ru_maxrss / 1024}))
"""
    out = subprocess.run([sys.executable, "-c", code, clip, "refine" if refine else "plain"],
                         check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def visage_run(binary, clip):
    """Runs `visage bench CLIP --quiet`; returns its figures with the process tree's CPU."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run([binary, "bench", clip, "--quiet"], check=True,
                         capture_output=True, text=True).stdout
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    report = json.loads(out)
    frames = report["frames"]
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"frames": frames, "fps": report["fps"], "cpu_ms": 1e3 * cpu / frames,
            "cpu_ms_own": 1e3 * report["cpu_s"] / frames, "rss_mib": report["peak_rss_mib"]}


def main():
    args = sys.argv[1:]
    pairs = 5
    if "--pairs" in args:
        i = args.index("--pairs")
        pairs = int(args[i + 1])
        del args[i:i + 2]
    refine = "--refine" in args
    if refine:
        args.remove("--refine")
    if len(args) < 2:
        sys.exit(__doc__)
    binary, clips = args[0], args[1:]
    print(f"load average at start: {open('/proc/loadavg').read().split()[:3]}; "
          f"MediaPipe refine_landmarks={refine}")
    for clip in clips:
        runs = {"mediapipe": [], "visage": []}
        for k in range(pairs):
            for tool in ("mediapipe", "visage"):
                r = mediapipe_run(clip, refine) if tool == "mediapipe" else visage_run(binary, clip)
                runs[tool].append(r)
                print(f"{clip} pair {k + 1} {tool}: " + ", ".join(
                    f"{key} {value:.1f}" if isinstance(value, float) else f"{key} {value}"
                    for key, value in r.items()))
        med = {tool: {key: statistics.median(r[key] for r in rs) for key in ("fps", "cpu_ms", "rss_mib")}
               for tool, rs in runs.items()}
        v, m = med["visage"], med["mediapipe"]
        print(f"{clip} medians: visage {v['fps']:.1f} fps, {v['cpu_ms']:.1f} CPU ms/frame, "
              f"{v['rss_mib']:.1f} MiB | MediaPipe {m['fps']:.1f} fps, {m['cpu_ms']:.1f} CPU ms/frame, "
              f"{m['rss_mib']:.1f} MiB | visage / MediaPipe fps {v['fps'] / m['fps']:.2f}, "
              f"CPU {v['cpu_ms'] / m['cpu_ms']:.2f}")
    print(f"load average at end: {open('/proc/loadavg').read().split()[:3]}")


if __name__ == "__main__":
    main()
