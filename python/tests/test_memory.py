"""Memory over a long session: the resident size's growth per frame, fitted over a stretch
of frames after the warm-up, stays at what the reconstructor keeps by design (each frame's
record, about 0.8 KB) — and the same measure sees a leak of a few kilobytes a frame."""

from __future__ import annotations

import numpy as np
from conftest import MODELS, frames, needs_data

import visage

#: Frames before the measure (buffers, the networks' arenas and the allocator settle), then
#: measured, the resident size read every SAMPLE_EVERY frames.
WARM_UP, MEASURED, SAMPLE_EVERY = 40, 160, 4

#: The most growth a frame may add: each frame's record is kept (about 0.8 KB), nothing else.
LIMIT_KB_PER_FRAME = 4.0


def resident_kb() -> float:
    """The process's resident size now (not its peak), kilobytes."""
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * 4096 / 1024


def growth_kb_per_frame(leak_kb: int = 0) -> float:
    """The slope of the resident size over MEASURED frames (least squares), with ``leak_kb``
    kept from every frame on purpose."""
    # The clip's first frames at half size (240 × 240), over and over.
    clip = [np.ascontiguousarray(f.image[::2, ::2]) for f in frames(20)]
    rec = visage.Reconstructor(models=MODELS)
    kept = []
    for i in range(WARM_UP):
        rec.process(clip[i % len(clip)])
    xs, ys = [], []
    for i in range(MEASURED):
        r = rec.process(clip[i % len(clip)])
        assert r.status != "no_face"
        if leak_kb:
            kept.append(np.ones(leak_kb * 256, np.float32))
        if i % SAMPLE_EVERY == 0:
            xs.append(i)
            ys.append(resident_kb())
    return float(np.polyfit(xs, ys, 1)[0])


@needs_data
def test_memory_stays_flat_over_a_long_session_and_the_measure_sees_a_small_leak():
    growth = growth_kb_per_frame()
    assert growth < LIMIT_KB_PER_FRAME, f"the resident size grew by {growth:.2f} KB a frame"
    # The same run leaking 2 × the limit a frame: the measure must see it.
    leaky = growth_kb_per_frame(leak_kb=int(2 * LIMIT_KB_PER_FRAME))
    assert leaky > LIMIT_KB_PER_FRAME, f"a leak of {2 * LIMIT_KB_PER_FRAME:.0f} KB a frame measured {leaky:.2f}"
