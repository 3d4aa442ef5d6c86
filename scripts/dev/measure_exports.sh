#!/usr/bin/env bash
# Dev-only: what the exports cost and weigh. For each clip, alternates `visage run` without and
# with `--glb --report` (REPEATS times each; wall time of the whole process), then one run with
# every output (`--report --glb --preview --ply`) for the sizes.
#   scripts/dev/measure_exports.sh [CLIP…]   (default: the shared sample clips; REPEATS=3)
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=target/release/visage
repeats="${REPEATS:-3}"
clips=("$@")
[ ${#clips[@]} -eq 0 ] && clips=(../shared/data/video/lp_d18.mp4 ../shared/data/video/lp_d13.mp4)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
wall() { /usr/bin/time -f %e "$@" 2>&1 >/dev/null | tail -1; }
for clip in "${clips[@]}"; do
  name=$(basename "$clip")
  for i in $(seq "$repeats"); do
    plain=$(wall "$bin" run "$clip" --out "$tmp/plain" --quiet)
    full=$(wall "$bin" run "$clip" --out "$tmp/ext" --glb --report --quiet)
    export_ms=$(python3 -c "import json;print(round(json.load(open('$tmp/ext/export.json'))['total_ms']))")
    echo "$name run $i: ${plain} s plain, ${full} s with --glb --report (exports ${export_ms} ms) load $(cut -d' ' -f1 /proc/loadavg)"
    rm -rf "$tmp/plain" "$tmp/ext"
  done
  "$bin" run "$clip" --out "$tmp/all" --report --glb --preview --ply --quiet
  python3 - "$tmp/all" <<'PY'
import json, os, sys
d = sys.argv[1]
e = json.load(open(os.path.join(d, "export.json")))
m = json.load(open(os.path.join(d, "metrics.json")))
size = lambda p: os.path.getsize(os.path.join(d, p))
total = sum(os.path.getsize(os.path.join(r, f)) for r, _, fs in os.walk(d) for f in fs)
ply = sum(os.path.getsize(os.path.join(d, "meshes", f)) for f in os.listdir(os.path.join(d, "meshes")))
print(f"  frames {m['summary']['frames']}, {m['frames'][-1]['time_s']:.1f} s of video")
for f in e["files"]:
    print(f"  {f['file']}: {f['bytes'] / 1e6:.2f} MB, {f['ms']:.0f} ms")
print(f"  sequence.pc2 {size('sequence.pc2') / 1e6:.2f} MB; PLY per frame (--ply) {ply / 1e6:.1f} MB")
print(f"  folder {total / 1e6:.1f} MB with the PLYs, {(total - ply) / 1e6:.1f} MB without")
print(f"  glb: {e['named_targets']} ARKit + {e['residual_targets']} residual targets, "
      f"{e['glb_rms_error_m'] * 1e3:.3f} mm RMS, {e['glb_max_error_m'] * 1e3:.3f} mm max; "
      f"ARKit curves explain {e['named_explained']:.2f} of the deformation; "
      f"texture {e['texture_frames']} frames, {e['texture_coverage'] * 100:.0f} % seen")
PY
done
