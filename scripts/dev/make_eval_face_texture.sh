#!/usr/bin/env bash
# Remakes crates/eval/data/face_texture.jpg, the real skin texture of the heads that
# `visage eval expressions` renders: visage's own pipeline runs on a real clip with the fitted
# face model as the mesh, and its fused texture (the first 2 s of frames, cos²-weighted; what
# the clip never saw takes the seen skin's mean colour) is in ICT-FaceKit's face UVs, the
# layout the renderer needs. Made by a script over two existing commands rather than a
# subcommand of its own: nothing new runs, and the file changes only when the pipeline's fit
# or texture fusion does.
#
# The clip's neutral moments only (lp_d18: 0–0.3 s, 1.4–1.9 s, 3.3–3.8 s; its other frames
# pucker, yawn or blink, and would paint an open mouth or closed eyes into the skin), cut into
# one short clip whose first 2 s are all they are.
#
# Usage: scripts/dev/make_eval_face_texture.sh [CLIP [SELECT]]
#   CLIP default ../shared/data/video/lp_d18.mp4; SELECT an FFmpeg select expression over t.
# Needs a release build of the binary (cargo build --release -p visage-cli) and FFmpeg.
set -euo pipefail
cd "$(dirname "$0")/../.."
visage="${VISAGE:-${CARGO_TARGET_DIR:-target}/release/visage}"
clip="${1:-../shared/data/video/lp_d18.mp4}"
select="${2:-between(t,0,0.3)+between(t,1.4,1.9)+between(t,3.3,3.8)}"
out=crates/eval/data/face_texture.jpg
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
ffmpeg -loglevel error -y -i "$clip" -vf "select='$select',setpts=N/30/TB" -r 30 \
  -c:v libx264 -crf 10 -pix_fmt yuv420p "$tmp/neutral.mp4"
"$visage" run "$tmp/neutral.mp4" --out "$tmp/run" --mesh model --texture --quiet
# A JPEG at quality ~90, at most 1024² (under 300 KB).
ffmpeg -loglevel error -y -i "$tmp/run/texture.png" \
  -vf "scale='min(iw,1024)':'min(ih,1024)':flags=lanczos" -q:v 3 "$out"
ls -l "$out"
