#!/usr/bin/env bash
# Times MediaPipe FaceMesh (PyPI mediapipe==0.10.21, landmarks only) and `visage bench` (the
# whole job) alternately on the same clips; see compare_mediapipe.py for what is measured.
#   scripts/dev/compare_mediapipe.sh [--pairs N] [--refine] [CLIP…]   (default: the two shared clips;
#   --refine: MediaPipe with its irises, refine_landmarks=True)
# Needs Python 3 with pip; the pinned environment is made under target/. Not a test requirement.
set -euo pipefail
cd "$(dirname "$0")/../.."
. scripts/dev/mediapipe_venv.sh
cargo build -q --release -p visage-cli
pairs=()
if [ "${1:-}" = --pairs ]; then pairs=(--pairs "$2"); shift 2; fi
if [ "${1:-}" = --refine ]; then pairs+=(--refine); shift; fi
clips=("$@")
[ ${#clips[@]} -gt 0 ] || clips=(../shared/data/video/lp_d18.mp4 ../shared/data/video/lp_d13.mp4)
"$venv/bin/python" scripts/dev/compare_mediapipe.py target/release/visage "${clips[@]}" "${pairs[@]}"
