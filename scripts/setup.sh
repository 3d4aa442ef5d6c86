#!/usr/bin/env bash
# Sets up visage on a fresh Debian machine and runs the main job on a sample.
#
#   scripts/setup.sh          install system packages, build (release), fetch the pinned
#                             MediaPipe models (npm, and the iris network from PyPI), run the
#                             sample job into out/sample/
#   scripts/setup.sh --ci     packages and models only (what the test suite needs)
#
# Needs: a Rust toolchain (cargo), Node.js/npm (for `npm pack`), Python 3 with pip (for
# `pip download` of the mediapipe wheel), apt-get as root (or the packages below already
# installed).
set -euo pipefail
cd "$(dirname "$0")/.."

mode=full
[ "${1:-}" = "--ci" ] && mode=ci

# System packages: FFmpeg's command-line tools decode video (crates/video).
need=()
command -v ffmpeg >/dev/null 2>&1 || need+=(ffmpeg)
command -v npm >/dev/null 2>&1 || need+=(npm)
python3 -m pip --version >/dev/null 2>&1 || need+=(python3-pip)
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

target_dir="${CARGO_TARGET_DIR:-target}"
if [ "$mode" = ci ]; then
  cargo build -q -p visage-cli
  bin="$target_dir/debug/visage"
else
  cargo build --release -p visage-cli
  bin="$target_dir/release/visage"
fi

# Model files: npm package @mediapipe/face_mesh and the iris network from the PyPI wheel
# mediapipe==0.10.21, pinned and sha256-checked, into models/.
"$bin" models fetch

[ "$mode" = ci ] && exit 0

# The main job on a sample: `visage run` on a real clip → a fused metric face mesh per frame, and
# shaded previews of a few frames (fused and raw) a person can open.
video=../shared/data/video/lp_d18.mp4
if [ ! -f "$video" ]; then
  echo "setup: done. No sample clip ($video: ../shared is absent); try: $bin run YOUR.mp4 --out out/run"
  exit 0
fi
out=out/sample
rm -rf "$out" && mkdir -p "$out"
"$bin" run "$video" --out "$out" --save-raw
# `visage run` writes the intrinsics it used (here the default 60° field of view) to camera.json.
for frame in 000000 000060 000120 000180; do
  "$bin" render "$out/meshes/$frame.ply" --intrinsics "$out/camera.json" --out "$out/preview_$frame.png"
  "$bin" render "$out/raw/$frame.ply" --intrinsics "$out/camera.json" --out "$out/preview_${frame}_raw.png"
done
echo "setup: sample written to $out/ (meshes/*.ply, blendshapes.csv, identity.obj, metrics.json, landmarks.json, previews preview_*.png)"
