"""What the Python tests share: the sample clip, the model files, the command line to compare
with, and the rule that a missing piece skips a test here and fails it under CI=true.

Needs ../shared (the sample clip), the model files and FFmpeg, as the Rust tests do.
``VISAGE_BIN`` names the ``visage`` binary the results are compared with (scripts/test.sh sets
it to the debug build's).
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path
from typing import List

import pytest

import visage

ROOT = Path(__file__).resolve().parents[2]
CLIP = ROOT.parent / "shared" / "data" / "video" / "lp_d18.mp4"
MODELS = Path(os.environ.get("VISAGE_MODELS", ROOT / "models"))
VISAGE_BIN = os.environ.get("VISAGE_BIN", str(ROOT / "target" / "debug" / "visage"))
CI = os.environ.get("CI") == "true"
HAVE_DATA = CLIP.is_file() and all((MODELS / f).is_file() for f in visage.MODEL_FILES)
if not HAVE_DATA and CI:
    raise RuntimeError(f"the Python tests need {CLIP} and the model files in {MODELS} (scripts/setup.sh)")
needs_data = pytest.mark.skipif(not HAVE_DATA, reason="needs ../shared and the model files (scripts/setup.sh)")


def frames(n: int) -> List[visage.Frame]:
    """The sample clip's first n frames, as visage.open reads them."""
    out = []
    for frame in visage.open(CLIP):
        out.append(frame)
        if len(out) == n:
            break
    return out


def visage_cli(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    """The command line (``VISAGE_BIN``) with ``args``; its output captured."""
    if not Path(VISAGE_BIN).is_file():
        if CI:
            raise RuntimeError(f"no visage binary at {VISAGE_BIN} (VISAGE_BIN; cargo build -p visage-cli)")
        pytest.skip(f"no visage binary at {VISAGE_BIN} (set VISAGE_BIN)")
    return subprocess.run([VISAGE_BIN, *args], check=check, capture_output=True, text=True)
