"""The Python call's cost over the Rust library's, per frame, on the same clip.

    python python/benchmarks/overhead.py CLIP [MODELS] [PASSES]

Decodes the clip first, then times `Reconstructor.process` on each frame (a fresh reconstructor
per pass, as `cargo run --release -p visage --example process_timing -- CLIP MODELS PASSES`
does on the Rust side). Prints the median and the mean in milliseconds.
"""

import sys
import time

import numpy as np

import visage


def main() -> None:
    clip = sys.argv[1]
    models = sys.argv[2] if len(sys.argv) > 2 else None
    passes = int(sys.argv[3]) if len(sys.argv) > 3 else 3
    frames = [(f.image, f.timestamp_s) for f in visage.open(clip)]
    ms = []
    for _ in range(passes):
        rec = visage.Reconstructor(models=models)
        for image, t in frames:
            start = time.perf_counter()
            rec.process(image, timestamp_s=t)
            ms.append((time.perf_counter() - start) * 1e3)
    print(f"{len(frames)} frames × {passes}: median {np.median(ms):.3f} ms, mean {np.mean(ms):.3f} ms per frame")


if __name__ == "__main__":
    main()
