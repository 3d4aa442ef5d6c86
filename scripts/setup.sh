#!/usr/bin/env bash
# Sets up visage on a fresh Debian machine and runs the main job on a sample.
#
#   scripts/setup.sh          install system packages, build the report's 3-D viewer (npm) and
#                             visage (release), fetch the pinned MediaPipe models (npm, and the
#                             iris network and full-range detector from PyPI), build the Python
#                             package into target/py-venv, run the sample job into out/sample/
#   scripts/setup.sh --ci     packages, viewer, models and the Kubernetes schema validator (PyPI,
#                             under target/) only — what the test suite needs —, and the Debian
#                             packages of the single-node Slurm cluster the batch test starts
#
# Needs: a Rust toolchain (cargo), Node.js/npm (for `npm pack` and the viewer's pinned
# packages), Python 3 with pip (for `pip download` of the mediapipe wheel), apt-get as root (or
# the packages below already installed).
set -euo pipefail
cd "$(dirname "$0")/.."

mode=full
[ "${1:-}" = "--ci" ] && mode=ci

# System packages: FFmpeg's command-line tools decode video and encode the preview
# (crates/video); Chromium runs the report's browser test (web/viewer/test).
need=()
command -v ffmpeg >/dev/null 2>&1 || need+=(ffmpeg)
[ -x /usr/bin/chromium ] || need+=(chromium)
command -v npm >/dev/null 2>&1 || need+=(npm)
python3 -m pip --version >/dev/null 2>&1 || need+=(python3-pip)
python3 -c "import venv, ensurepip" >/dev/null 2>&1 || need+=(python3-venv)
# The test suite's single-node Slurm cluster (scripts/test_slurm.sh runs the batch deploy
# script on it): only for the tests, without the packages' recommendations.
slurm=()
if [ "$mode" = ci ]; then
  for tool in slurmctld slurmd sbatch munged; do
    command -v "$tool" >/dev/null 2>&1 || [ -x "/usr/sbin/$tool" ] || { slurm=(slurmctld slurmd slurm-client munge); break; }
  done
fi
if [ ${#need[@]} -gt 0 ]; then
  if [ "$(id -u)" = 0 ]; then
    echo "setup: installing ${need[*]} (apt)"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${need[@]}" >/dev/null
  else
    echo "setup: please install: ${need[*]} (e.g. sudo apt-get install ${need[*]})" >&2
    exit 1
  fi
fi
if [ ${#slurm[@]} -gt 0 ]; then
  if [ "$(id -u)" = 0 ]; then
    echo "setup: installing ${slurm[*]} (apt, for the batch tests)"
    [ ${#need[@]} -gt 0 ] || apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${slurm[@]}" >/dev/null
  else
    echo "setup: not root: the Slurm test will be skipped (it needs ${slurm[*]})" >&2
  fi
fi

# The report's 3-D viewer: three.js and the viewer bundled into one script
# (web/viewer/dist/viewer.js), which the build embeds in visage; the glTF validator and the
# browser test's driver come with it (versions pinned in web/viewer/package-lock.json).
web/viewer/build.sh >/dev/null

target_dir="${CARGO_TARGET_DIR:-target}"
if [ "$mode" = ci ]; then
  cargo build -q -p visage-cli
  bin="$target_dir/debug/visage"
else
  cargo build --release -p visage-cli
  bin="$target_dir/release/visage"
fi

# Model files: npm package @mediapipe/face_mesh, and the iris network and the full-range face
# detector from the PyPI wheel mediapipe==0.10.21, pinned and sha256-checked, into models/.
"$bin" models fetch

# The Kubernetes schema validator for the deploy files' test (scripts/test_deploy.sh), pinned,
# in a virtual environment under the build folder.
venv="$target_dir/deploy-venv"
if ! "$venv/bin/kubernetes-validate" --version >/dev/null 2>&1; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q --no-cache-dir kubernetes-validate==1.37.0
fi

# Real clients for `visage live`'s tests: the PyPI packages pylivelinkface, which decodes the
# iPhone app's Live Link packets, and python-osc (the VMC protocol's OSC), pinned, in a virtual
# environment under the build folder.
live_venv="$target_dir/live-venv"
if ! "$live_venv/bin/python" -c "import pylivelinkface, pythonosc" >/dev/null 2>&1; then
  python3 -m venv "$live_venv"
  "$live_venv/bin/pip" install -q --no-cache-dir pylivelinkface==0.1 timecode==1.5.1 numpy==2.4.6 \
    python-osc==1.10.2
fi

# The Python package (python/; its native module is the crate crates/python): maturin and
# pytest, pinned, in a virtual environment under the build folder, and the model files copied
# into the package with their notices (MediaPipe's, Apache-2.0; ICT-FaceKit's, MIT, for the face
# model built into the module) so that its wheel carries them. The wheel is built and installed there: by
# the test command with the test build's profile (scripts/test.sh), here optimised.
py_venv="$target_dir/py-venv"
# OpenCV (headless) and matplotlib: the package's example (python/examples), run by its tests.
if [ ! -x "$py_venv/bin/maturin" ] || ! "$py_venv/bin/python" -c "import pytest, numpy, cv2, matplotlib" >/dev/null 2>&1; then
  python3 -m venv "$py_venv"
  "$py_venv/bin/pip" install -q --no-cache-dir maturin==1.16.0 pytest==9.2.0 numpy==2.4.6 \
    opencv-python-headless==5.1.0.95 matplotlib==3.11.2
fi
rm -rf python/visage/models
mkdir -p python/visage/models
# Every model file but the attention face mesh, which the pipeline the package wraps does not run.
for f in "${VISAGE_MODELS:-models}"/*; do
  [ "$(basename "$f")" = face_landmark_with_attention.tflite ] || cp "$f" python/visage/models/
done
cp crates/morphable/data/LICENSE-ICT-FaceKit python/visage/models/

[ "$mode" = ci ] && exit 0

scripts/build_python.sh release

# The main job on a sample: `visage run` on a real clip → a fused metric face mesh per frame, and
# shaded previews of a few frames (fused and raw) a person can open.
video=../shared/data/video/lp_d18.mp4
if [ ! -f "$video" ]; then
  echo "setup: done. No sample clip ($video: ../shared is absent); try: $bin run YOUR.mp4 --out out/run"
  exit 0
fi
out=out/sample
rm -rf "$out" && mkdir -p "$out"
# Every output: the point cache with its OBJ, the animated glb with its texture, the plots, the
# offline report and the preview video.
"$bin" run "$video" --out "$out" --report --glb --preview
# A textured turntable of one frame, rendered by visage's rasteriser from the point cache.
"$bin" render "$out/sequence.pc2" --frame 60 --intrinsics "$out/camera.json" \
  --texture "$out/texture.png" --views turntable:8 --out "$out/turntable.png"
echo "setup: sample written to $out/ (report.html, sequence.glb, preview.mp4, sequence.pc2 + mesh.obj, blendshapes.csv, metrics.json; turntable_*.png)"
