"""The Python package against the Rust library and the command line, on a shared clip.

Needs ../shared (the sample clip), the model files and FFmpeg, as the Rust tests do; without
them the tests skip, and under CI=true they fail. ``VISAGE_BIN`` names the ``visage`` binary
the results are compared with (scripts/test.sh sets it).
"""

from __future__ import annotations

import os
import resource
import subprocess
import threading
from pathlib import Path

import numpy as np
import pytest

import visage

ROOT = Path(__file__).resolve().parents[2]
CLIP = ROOT.parent / "shared" / "data" / "video" / "lp_d18.mp4"
MODELS = Path(os.environ.get("VISAGE_MODELS", ROOT / "models"))
HAVE_DATA = CLIP.is_file() and all((MODELS / f).is_file() for f in visage.MODEL_FILES)
if not HAVE_DATA and os.environ.get("CI") == "true":
    raise RuntimeError(f"the Python tests need {CLIP} and the model files in {MODELS} (scripts/setup.sh)")
needs_data = pytest.mark.skipif(not HAVE_DATA, reason="needs ../shared and the model files (scripts/setup.sh)")


def frames(n: int):
    """The sample clip's first n frames, as visage.open reads them."""
    out = []
    for frame in visage.open(CLIP):
        out.append(frame)
        if len(out) == n:
            break
    return out


@needs_data
def test_a_frame_gives_a_metric_mesh_weights_and_pose_with_their_shapes_and_types():
    # The model files the wheel carries (scripts/setup.sh copies them in), unless told.
    bundled = Path(visage.__file__).parent / "models"
    assert all((bundled / f).is_file() for f in visage.MODEL_FILES) or os.environ.get("CI") != "true"
    rec = visage.Reconstructor()
    results = [rec.process(f.image, timestamp_s=f.timestamp_s) for f in frames(5)]
    r = results[-1]
    assert r.status == "solved"
    assert r.vertices.dtype == np.float32 and r.vertices.shape == (1833, 3)
    # A face about half a metre in front of the camera.
    assert 0.2 < float(np.median(r.vertices[:, 2])) < 1.5
    assert r.landmarks.dtype == np.float32 and r.landmarks.shape == (468, 2)
    assert r.blendshape_array.dtype == np.float32 and r.blendshape_array.shape == (52,)
    assert list(r.blendshapes) == list(visage.ARKIT_BLENDSHAPES)
    assert all(0.0 <= w <= 1.0 for w in r.blendshapes.values())
    assert r.head_pose.shape == (4, 4) and np.allclose(r.head_pose[:3, :3] @ r.head_pose[:3, :3].T, np.eye(3), atol=1e-6)
    assert len(r.head_angles) == 3
    assert r.timings_ms["track"] > 0.0 and r.timings_ms["fit"] > 0.0
    faces = rec.faces
    assert faces.dtype == np.int32 and faces.shape[1] == 3 and faces.max() < 1833
    fx, fy, cx, cy = rec.intrinsics
    assert fx > 0 and cx == pytest.approx(239.5)


@needs_data
def test_results_equal_the_command_lines_run_bit_for_bit(tmp_path):
    """The same frames, the same options (causal: latency 0): the same weights and meshes."""
    n = 40
    out = tmp_path / "run"
    binary = os.environ.get("VISAGE_BIN", str(ROOT / "target" / "debug" / "visage"))
    subprocess.run(
        [binary, "run", str(CLIP), "--latency", "0", "--max-frames", str(n), "--out", str(out),
         "--models", str(MODELS), "--quiet"],
        check=True,
    )
    run = visage.read_run(out)
    rec = visage.Reconstructor(models=MODELS)
    weights, vertices = [], []
    for f in frames(n):
        r = rec.process(f.image, timestamp_s=f.timestamp_s)
        weights.append(r.blendshape_array)
        vertices.append(r.vertices)
    assert run.vertices.shape == (n, 1833, 3)
    assert np.array_equal(np.stack(vertices), run.vertices)
    # The CSV has 10 decimals of each float32 weight.
    assert np.abs(np.stack(weights) - run.blendshapes).max() < 1e-9
    assert np.array_equal(rec.faces, run.faces)


@needs_data
def test_bad_frames_and_inputs_raise_clear_exceptions(tmp_path):
    rec = visage.Reconstructor(models=MODELS)
    with pytest.raises(ValueError, match="dtype is float32"):
        rec.process(np.zeros((48, 64, 3), np.float32))
    with pytest.raises(ValueError, match=r"shape is \(48, 64\)"):
        rec.process(np.zeros((48, 64), np.uint8))
    with pytest.raises(ValueError, match=r"shape is \(48, 64, 4\)"):
        rec.process(np.zeros((48, 64, 4), np.uint8))
    with pytest.raises(ValueError, match="not list"):
        rec.process([[0, 0, 0]])
    r = rec.process(np.zeros((48, 64, 3), np.uint8))
    assert r.status == "no_face" and r.vertices is None and r.blendshapes == {}
    with pytest.raises(ValueError, match="64×48"):
        rec.process(np.zeros((64, 48, 3), np.uint8))
    # A view of every other column (not C-contiguous) is read as it looks.
    r = rec.process(np.zeros((48, 128, 3), np.uint8)[:, ::2])
    assert r.status == "no_face"
    missing = tmp_path / "nothing.mp4"
    with pytest.raises(visage.VisageError, match="nothing.mp4"):
        visage.open(missing)
    with pytest.raises(visage.VisageError, match="models"):
        visage.Reconstructor(models=tmp_path).process(np.zeros((48, 64, 3), np.uint8))
    with pytest.raises(ValueError, match="fov_deg 200: must lie between"):
        visage.Reconstructor(fov_deg=200.0)
    with pytest.raises(visage.VisageError, match="not a visage run folder"):
        visage.read_run(tmp_path)


@needs_data
def test_two_reconstructors_on_two_threads_give_what_each_gives_alone():
    clip = frames(20)
    alone = visage.Reconstructor(models=MODELS)
    expected = [alone.process(f.image, f.timestamp_s).blendshape_array for f in clip]
    got = {}

    def work(key):
        rec = visage.Reconstructor(models=MODELS)
        got[key] = [rec.process(f.image, f.timestamp_s).blendshape_array for f in clip]

    threads = [threading.Thread(target=work, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k in range(2):
        assert np.array_equal(np.stack(got[k]), np.stack(expected))


@needs_data
def test_memory_stays_flat_over_two_thousand_frames():
    clip = [f.image for f in frames(50)]
    rec = visage.Reconstructor(models=MODELS)

    def rss_mb():
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0

    for i in range(200):
        rec.process(clip[i % 50])
    after_200 = rss_mb()
    for i in range(1800):
        rec.process(clip[i % 50])
    growth = rss_mb() - after_200
    # Each frame's record is kept (about 0.8 KB): 1.5 MB over 1,800 frames.
    assert growth < 10.0, f"peak resident size grew by {growth:.1f} MB over 1,800 frames"
