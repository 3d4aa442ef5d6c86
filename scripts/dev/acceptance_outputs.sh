#!/usr/bin/env bash
# Runs the commands whose outputs a refactor must leave byte for byte as they were, into OUT:
# `visage run` on both shared clips (streaming and clip mode, with --glb --report), a run
# continued with --resume, --faces all with PLYs, `visage batch` on a two-clip manifest and
# the reconstruct example. Compare two such folders with scripts/dev/compare_outputs.py.
#
#   scripts/dev/acceptance_outputs.sh target/release/visage target/release/examples/reconstruct OUT
set -uo pipefail
bin=$1 example=$2 out=$3
clips="$(cd "$(dirname "$0")/../../.." && pwd)/shared/data/video"
export VISAGE_MODELS="${VISAGE_MODELS:-$(cd "$(dirname "$0")/../.." && pwd)/models}"
rm -rf "$out" && mkdir -p "$out"
for c in lp_d13 lp_d18; do
  "$bin" run "$clips/$c.mp4" --out "$out/$c-stream" --glb --report --quiet; echo "$c stream: exit $?"
  "$bin" run "$clips/$c.mp4" --out "$out/$c-clip" --mode clip --glb --report --quiet; echo "$c clip: exit $?"
done
"$bin" run "$clips/lp_d18.mp4" --out "$out/resume" --max-frames 20 --quiet; echo "first part: exit $?"
"$bin" run "$clips/lp_d18.mp4" --out "$out/resume" --max-frames 45 --resume --quiet; echo "resumed: exit $?"
"$bin" run "$clips/lp_d18.mp4" --out "$out/faces" --max-frames 15 --faces all --ply --quiet; echo "faces all: exit $?"
printf '%s\n' "$clips/lp_d13.mp4" "$clips/lp_d18.mp4" > "$out/manifest.txt"
"$bin" batch "$out/manifest.txt" --out "$out/batch" -- --max-frames 25 --glb >"$out/batch.stdout" 2>"$out/batch.stderr"
echo "batch: exit $?"
mkdir -p "$out/example" && "$example" "$clips/lp_d18.mp4" "$out/example" >"$out/example.stdout" 2>&1
echo "example: exit $?"
