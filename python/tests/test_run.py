"""visage.run against `visage run`: the same files (the exports, every face, an RGB-D recording
included), the same errors; its progress, the GIL released while it works, and a run stopped
from Python."""

from __future__ import annotations

import importlib.util
import json
import threading

import numpy as np
import pytest
from conftest import CI, CLIP, MODELS, frames, needs_data, visage_cli

import visage

#: Files whose bytes hold no clock: equal bit for bit between the two runs.
DETERMINISTIC = ("sequence.pc2", "mesh.obj", "mesh.mtl", "blendshapes.csv", "camera.json", "landmarks.json")


def files(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@needs_data
def test_run_writes_the_command_lines_files(tmp_path):
    n = 12
    cli, py = tmp_path / "cli", tmp_path / "py"
    visage_cli("run", str(CLIP), "--out", str(cli), "--max-frames", str(n), "--models", str(MODELS), "--ply", "--quiet")
    calls = []
    result = visage.run(CLIP, py, max_frames=n, models=MODELS, ply=True, progress=lambda *a: calls.append(a))
    assert files(py) == files(cli)
    for name in DETERMINISTIC + tuple(f for f in files(cli) if f.endswith(".ply")):
        assert (py / name).read_bytes() == (cli / name).read_bytes(), name
    # metrics.json: the same records but for the clocks (stage times, frames per second, memory).
    m_py, m_cli = (json.loads((d / "metrics.json").read_text()) for d in (py, cli))
    assert m_py["status"] == m_cli["status"] == "complete"
    assert m_py["parameters"] == m_cli["parameters"] and m_py["input"] == m_cli["input"]
    assert [f["status"] for f in m_py["frames"]] == [f["status"] for f in m_cli["frames"]]
    assert m_py["summary"]["quality"] == m_cli["summary"]["quality"]
    assert (result.frames, result.meshed, result.kept) == (n, n, n)
    assert result.summary["frames"] == n
    assert calls == [(k, n) for k in range(1, n + 1)]


@needs_data
def test_run_makes_the_command_lines_exports(tmp_path):
    """glb=True, report=True write what --glb --report write (the glb, the texture, the plots,
    the report and export.json), from the frames the run kept."""
    n = 8
    cli, py = tmp_path / "cli", tmp_path / "py"
    visage_cli("run", str(CLIP), "--out", str(cli), "--max-frames", str(n), "--models", str(MODELS),
               "--glb", "--report", "--quiet")
    result = visage.run(CLIP, py, max_frames=n, models=MODELS, glb=True, report=True)
    assert files(py) == files(cli)
    for name in ("sequence.glb", "texture.png", "report.html", "export.json"):
        assert (py / name).is_file(), name
    exported = json.loads((cli / "export.json").read_text())
    assert result.exports is not None
    assert [f["file"] for f in result.exports["files"]] == [f["file"] for f in exported["files"]]
    assert result.exports["named_targets"] == exported["named_targets"]
    # The texture is fused from the same kept frames.
    assert (py / "texture.png").read_bytes() == (cli / "texture.png").read_bytes()


@needs_data
def test_run_over_every_face_writes_the_command_lines_folders(tmp_path):
    n = 4
    cli, py = tmp_path / "cli", tmp_path / "py"
    visage_cli("run", str(CLIP), "--out", str(cli), "--max-frames", str(n), "--models", str(MODELS),
               "--faces", "all", "--quiet")
    result = visage.run(CLIP, py, max_frames=n, models=MODELS, faces="all")
    assert files(py) == files(cli)
    f_py, f_cli = (json.loads((d / "faces.json").read_text()) for d in (py, cli))
    assert f_py == f_cli
    assert [r.out_dir for r in result.faces] == [py / f["folder"] for f in f_cli["faces"]]
    assert result.meshed == sum(f["frames_meshed"] for f in f_cli["faces"])


@needs_data
@pytest.mark.skipif(importlib.util.find_spec("cv2") is None and not CI, reason="needs cv2 (scripts/setup.sh)")
def test_run_reads_an_rgbd_recording_as_the_command_line(tmp_path):
    """rgbd= is --rgbd: a recording of rgb/ and depth/ (the sample clip's frames, a flat 16-bit
    depth map in millimetres each) fused frame by frame, the same files and parameters."""
    import cv2  # opencv-python-headless, pinned beside the package (scripts/setup.sh)

    recording = tmp_path / "recording"
    (recording / "rgb").mkdir(parents=True)
    (recording / "depth").mkdir()
    for frame in frames(4):
        name = f"frame{frame.index:03d}.png"
        cv2.imwrite(str(recording / "rgb" / name), cv2.cvtColor(frame.image, cv2.COLOR_RGB2BGR))
        cv2.imwrite(str(recording / "depth" / name), np.full(frame.image.shape[:2], 600, dtype=np.uint16))
    cli, py = tmp_path / "cli", tmp_path / "py"
    visage_cli("run", "--rgbd", str(recording), "--out", str(cli), "--models", str(MODELS), "--quiet")
    result = visage.run(None, py, rgbd=recording, models=MODELS)
    assert files(py) == files(cli)
    m_py, m_cli = (json.loads((d / "metrics.json").read_text()) for d in (py, cli))
    for key in ("parameters", "intrinsics", "input"):
        assert m_py[key] == m_cli[key], key
    assert m_py["parameters"]["depth"] == m_cli["parameters"]["depth"] != "face"
    assert result.frames == 4
    assert (py / "sequence.pc2").read_bytes() == (cli / "sequence.pc2").read_bytes()


@needs_data
def test_run_releases_the_gil_and_a_raising_callback_stops_it(tmp_path):
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(None)
            stop.wait(0.001)

    counter = threading.Thread(target=count)
    counter.start()

    def progress(done, total):
        if done == 3:
            raise KeyError("enough")

    try:
        with pytest.raises(KeyError, match="enough"):
            visage.run(CLIP, tmp_path / "out", max_frames=30, models=MODELS, progress=progress)
    finally:
        stop.set()
        counter.join()
    # The other thread ran while frames were processed (each takes milliseconds).
    assert len(ticks) > 20
    metrics = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert metrics["status"] == "interrupted"
    assert 3 <= len(metrics["frames"]) < 30


@needs_data
@pytest.mark.parametrize(
    "flags, options",
    [
        (["--fov-deg", "200"], {"fov_deg": 200.0}),
        (["--every", "0"], {"every": 0}),
        (["--subdivision", "0"], {"subdivision": 0}),
        (["--depth", "no-such-folder"], {"depth": "no-such-folder"}),
    ],
)
def test_run_fails_with_the_command_lines_message(tmp_path, flags, options):
    cli_out, py_out = tmp_path / "cli", tmp_path / "py"
    cli = visage_cli("run", str(CLIP), "--out", str(cli_out), "--models", str(MODELS), *flags, check=False)
    assert cli.returncode == 2
    message = cli.stderr.strip().removeprefix("error: ")
    with pytest.raises(visage.VisageError) as raised:
        visage.run(CLIP, py_out, models=MODELS, **options)
    assert str(raised.value) == message.replace(str(cli_out), str(py_out))


@needs_data
def test_run_refuses_what_the_command_line_refuses(tmp_path):
    missing = tmp_path / "nothing.mp4"
    cli = visage_cli("run", str(missing), "--out", str(tmp_path / "a"), check=False)
    with pytest.raises(visage.VisageError) as raised:
        visage.run(missing, tmp_path / "b")
    assert str(raised.value) == cli.stderr.strip().removeprefix("error: ")
    full = tmp_path / "full"
    full.mkdir()
    (full / "notes.txt").write_text("mine")
    cli = visage_cli("run", str(CLIP), "--out", str(full), check=False)
    with pytest.raises(visage.VisageError) as raised:
        visage.run(CLIP, full)
    assert str(raised.value) == cli.stderr.strip().removeprefix("error: ")
    with pytest.raises(ValueError, match='mesh="cube": must be one of "face", "image", "model"'):
        visage.run(CLIP, tmp_path / "c", mesh="cube")
    with pytest.raises(ValueError, match='smoothing=fast: neither a positive number nor "off"'):
        visage.run(CLIP, tmp_path / "c", smoothing="fast")
    with pytest.raises(ValueError, match="overwrite and resume cannot be given together"):
        visage.run(CLIP, tmp_path / "c", overwrite=True, resume=True)
    with pytest.raises(ValueError, match='faces="every": must be one of "largest", "all"'):
        visage.run(CLIP, tmp_path / "c", faces="every")
    with pytest.raises(ValueError, match="input and rgbd cannot be given together"):
        visage.run(CLIP, tmp_path / "c", rgbd=tmp_path)
    with pytest.raises(ValueError, match="keep_depth_edges needs rgbd"):
        visage.run(CLIP, tmp_path / "c", keep_depth_edges=True)
    with pytest.raises(ValueError, match="input or rgbd must be given"):
        visage.run(None, tmp_path / "c")
    # An option the command line does not have.
    with pytest.raises(TypeError, match="gltf"):
        visage.run(CLIP, tmp_path / "c", gltf=True)


@needs_data
def test_run_sets_what_the_flags_set(tmp_path):
    """Every option beside its flag: the run's recorded parameters, camera and frame selection
    are the command line's (the two map options to the library each on their own)."""
    cli, py = tmp_path / "cli", tmp_path / "py"
    visage_cli("run", str(CLIP), "--out", str(cli), "--models", str(MODELS), "--quiet", "--max-frames", "3",
               "--every", "2", "--fov-deg", "50", "--smoothing", "off", "--latency", "0", "--lambda", "2",
               "--mu", "3", "--subdivision", "3", "--keypoints", "--fair", "2", "--mesh", "model",
               "--depth", "model")
    visage.run(CLIP, py, models=MODELS, max_frames=3, every=2, fov_deg=50.0, smoothing="off", latency=0,
               lambda_=2.0, mu=3.0, subdivision=3, keypoints=True, fair=2.0, mesh="model", depth="model")
    m_py, m_cli = (json.loads((d / "metrics.json").read_text()) for d in (py, cli))
    for key in ("parameters", "intrinsics", "selection", "mesh"):
        assert m_py[key] == m_cli[key], key
    assert m_py["parameters"]["keypoint_motion"] and m_py["parameters"]["landmark_smoothing"] is None
    assert (py / "blendshapes.csv").read_bytes() == (cli / "blendshapes.csv").read_bytes()
