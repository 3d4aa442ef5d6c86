#!/usr/bin/env bash
# Blinks against MediaPipe's refined eyelids (PyPI mediapipe==0.10.21, refine_landmarks=True, its
# attention mesh): runs MediaPipe and `visage run` on each clip and prints, per clip, the mean
# EyeBlink at frames where MediaPipe shows both eyes closed (aperture under 0.45 of its median),
# the 95th percentile where both are open (over 0.75), and how far the gaze strays from its
# pre-blink value during each closure.
#   scripts/dev/compare_lids.sh [CLIP…]   (default: the two shared clips)
# Needs Python 3 with pip; the pinned environment is made under target/. Not a test requirement.
set -euo pipefail
cd "$(dirname "$0")/../.."
. scripts/dev/mediapipe_venv.sh
cargo build -q --release -p visage-cli
clips=("$@")
[ ${#clips[@]} -gt 0 ] || clips=(../shared/data/video/lp_d18.mp4 ../shared/data/video/lp_d13.mp4)
work=target/compare-lids
mkdir -p "$work"
pairs=()
for clip in "${clips[@]}"; do
  name=$(basename "${clip%.*}")
  "$venv/bin/python" scripts/dev/mediapipe_lids.py "$clip" > "$work/$name.mediapipe.csv" 2>/dev/null
  target/release/visage run "$clip" --out "$work/$name" --overwrite > /dev/null
  pairs+=("$work/$name/blendshapes.csv" "$work/$name.mediapipe.csv")
done
python3 scripts/dev/compare_lids.py "${pairs[@]}"
