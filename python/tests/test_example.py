"""The package's example runs on the sample clip as a user runs it (OpenCV, matplotlib)."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys

import pytest
from conftest import CI, CLIP, MODELS, ROOT, needs_data

EXAMPLE = ROOT / "python" / "examples" / "jaw_open_opencv.py"
MISSING = [m for m in ("cv2", "matplotlib") if importlib.util.find_spec(m) is None]
if MISSING and CI:
    raise RuntimeError(f"the example's test needs {', '.join(MISSING)} in the virtual environment (scripts/setup.sh)")


@needs_data
@pytest.mark.skipif(bool(MISSING), reason=f"needs {', '.join(MISSING)} (scripts/setup.sh installs them)")
def test_the_opencv_example_plots_jaw_open_over_the_clip(tmp_path):
    png = tmp_path / "jaw.png"
    env = dict(os.environ, VISAGE_MODELS=str(MODELS))
    out = subprocess.run([sys.executable, str(EXAMPLE), str(CLIP), str(png)], env=env,
                         check=True, capture_output=True, text=True)
    assert out.stdout.strip() == f"{png}: JawOpen over 216 frames, 216 with a face"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
