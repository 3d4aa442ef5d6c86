"""visage.Reconstructor against the command line's run of the same frames, its shapes and
types, its errors, threads and memory."""

from __future__ import annotations

import json
import os
import threading
from pathlib import Path

import numpy as np
import pytest
from conftest import CLIP, MODELS, frames, needs_data, visage_cli

import visage


@needs_data
def test_a_frame_gives_a_metric_mesh_weights_pose_irises_and_identity_with_their_shapes_and_types():
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
    assert r.landmarks.dtype == np.float32 and r.landmarks.shape == (478, 2)
    # The irises (468: the subject's right, 473: the left) lie between their eye's corners.
    assert r.has_irises and np.isfinite(r.landmarks).all()
    for centre, corners in ((468, (33, 133)), (473, (362, 263))):
        xs = sorted(r.landmarks[list(corners), 0])
        assert xs[0] < r.landmarks[centre, 0] < xs[1]
        rim = r.landmarks[centre + 1 : centre + 5]
        radius = np.linalg.norm(rim - r.landmarks[centre], axis=1)
        # An iris is about 12 mm across, an eye about 30 mm from corner to corner.
        assert (radius > 1.0).all() and (radius < 0.5 * (xs[1] - xs[0])).all()
    assert r.blendshape_array.dtype == np.float32 and r.blendshape_array.shape == (52,)
    assert list(r.blendshapes) == list(visage.ARKIT_BLENDSHAPES)
    assert all(0.0 <= w <= 1.0 for w in r.blendshapes.values())
    assert r.head_pose.shape == (4, 4) and np.allclose(r.head_pose[:3, :3] @ r.head_pose[:3, :3].T, np.eye(3), atol=1e-6)
    assert len(r.head_angles) == 3
    assert r.identity.dtype == np.float64 and r.identity.ndim == 1 and r.identity.size > 0
    # The identity firms up frame by frame.
    assert not np.array_equal(results[1].identity, r.identity)
    assert r.timings_ms["track"] > 0.0 and r.timings_ms["fit"] > 0.0
    faces = rec.faces
    assert faces.dtype == np.int32 and faces.shape[1] == 3 and faces.max() < 1833
    assert rec.uvs.dtype == np.float32 and rec.uvs.shape == (1833, 2)
    assert ((rec.uvs >= 0.0) & (rec.uvs <= 1.0)).all()
    fx, fy, cx, cy = rec.intrinsics
    assert fx > 0 and cx == pytest.approx(239.5)


@needs_data
def test_without_the_iris_network_the_iris_rows_are_nan(tmp_path):
    models = tmp_path / "models"
    models.mkdir()
    for f in MODELS.iterdir():
        if f.name != "iris_landmark.tflite":
            (models / f.name).symlink_to(f.resolve())
    rec = visage.Reconstructor(models=models)
    r = [rec.process(f.image, f.timestamp_s) for f in frames(2)][-1]
    assert not r.has_irises and r.landmarks.shape == (478, 2)
    assert np.isfinite(r.landmarks[:468]).all() and np.isnan(r.landmarks[468:]).all()


def run_cli(tmp_path, n, latency):
    out = tmp_path / f"run-latency-{latency}"
    visage_cli("run", str(CLIP), "--latency", str(latency), "--max-frames", str(n), "--out", str(out),
               "--models", str(MODELS), "--quiet")
    return visage.read_run(out)


@needs_data
def test_results_equal_the_command_lines_run_bit_for_bit(tmp_path):
    """The same frames, the same options (causal: latency 0): the same weights and meshes."""
    n = 40
    run = run_cli(tmp_path, n, 0)
    rec = visage.Reconstructor(models=MODELS)
    results = [rec.process(f.image, timestamp_s=f.timestamp_s) for f in frames(n)]
    assert run.vertices.shape == (n, 1833, 3)
    assert np.array_equal(np.stack([r.vertices for r in results]), run.vertices)
    # The CSV has 10 decimals of each float32 weight.
    assert np.abs(np.stack([r.blendshape_array for r in results]) - run.blendshapes).max() < 1e-9
    assert np.array_equal(rec.faces, run.faces)
    tracked = np.array([f["faces"][0]["landmarks"] for f in run.landmarks["frames"]])[:, :, :2]
    assert np.array_equal(np.stack([r.landmarks[:468] for r in results]), tracked.astype(np.float32))


@needs_data
def test_push_with_latency_one_equals_the_command_lines_default_run(tmp_path):
    """A frame of look-ahead (visage run's default): push gives the frame before, end the last."""
    n = 20
    run = run_cli(tmp_path, n, 1)
    rec = visage.Reconstructor(models=MODELS, latency=1)
    clip = frames(n)
    first = rec.push(clip[0].image, clip[0].timestamp_s)
    assert first == []
    results = []
    for f in clip[1:]:
        done = rec.push(f.image, f.timestamp_s)
        assert [r.index for r in done] == [f.index - 1]
        results += done
    results += rec.end()
    assert [r.index for r in results] == list(range(n))
    assert np.array_equal(np.stack([r.vertices for r in results]), run.vertices)
    assert np.abs(np.stack([r.blendshape_array for r in results]) - run.blendshapes).max() < 1e-9


@needs_data
def test_bad_frames_options_and_inputs_raise_clear_exceptions(tmp_path):
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
    assert r.status == "no_face" and r.vertices is None and r.landmarks is None and r.blendshapes == {}
    with pytest.raises(ValueError, match="64×48"):
        rec.process(np.zeros((64, 48, 3), np.uint8))
    # A view of every other column (not C-contiguous) is read as it looks.
    r = rec.process(np.zeros((48, 128, 3), np.uint8)[:, ::2])
    assert r.status == "no_face"
    with pytest.raises(ValueError, match="with latency=1 use push"):
        visage.Reconstructor(latency=1).process(np.zeros((48, 64, 3), np.uint8))
    with pytest.raises(ValueError, match="visage.run"):
        visage.Reconstructor(mode="clip")
    with pytest.raises(ValueError, match='mode="fast"'):
        visage.Reconstructor(mode="fast")
    with pytest.raises(ValueError, match="cannot be given together"):
        visage.Reconstructor(fov_deg=60.0, intrinsics=(500.0, 500.0, 32.0, 24.0))
    with pytest.raises(ValueError, match=r"shape is \(2, 2\)"):
        visage.Reconstructor(intrinsics=np.eye(2))
    with pytest.raises(visage.VisageError, match="missing.json"):
        visage.Reconstructor(intrinsics=tmp_path / "missing.json")
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
def test_a_camera_matrix_or_an_intrinsics_file_sets_the_camera(tmp_path):
    image = frames(1)[0].image
    k = np.array([[400.0, 0.0, 240.0], [0.0, 410.0, 230.0], [0.0, 0.0, 1.0]])
    rec = visage.Reconstructor(intrinsics=k, models=MODELS)
    rec.process(image)
    assert rec.intrinsics == (400.0, 410.0, 240.0, 230.0)
    camera = tmp_path / "camera.json"
    camera.write_text(json.dumps({"width": 480, "height": 480, "fx": 500.0, "fy": 500.0, "cx": 239.5, "cy": 239.5}))
    rec = visage.Reconstructor(intrinsics=camera, models=MODELS)
    rec.process(image)
    assert rec.intrinsics == (500.0, 500.0, 239.5, 239.5)
    with pytest.raises(visage.VisageError, match=r"camera.json: intrinsics are for another image size than the frames \(240×240\)"):
        visage.Reconstructor(intrinsics=camera, models=MODELS).process(np.ascontiguousarray(image[::2, ::2]))


@needs_data
def test_two_reconstructors_on_two_threads_give_what_each_gives_alone():
    clip = frames(12)
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
def test_a_bgr_frame_is_warned_about_once_and_an_rgb_one_is_not():
    import warnings

    frame = frames(1)[0].image
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning for the RGB frames
        rec = visage.Reconstructor()
        rec.process(frame)
        rec.process(frame)
    rec = visage.Reconstructor()
    with pytest.warns(UserWarning, match="BGR"):
        rec.process(np.ascontiguousarray(frame[:, :, ::-1]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # once per reconstructor
        rec.process(np.ascontiguousarray(frame[:, :, ::-1]))
