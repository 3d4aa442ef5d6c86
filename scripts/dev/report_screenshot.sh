#!/usr/bin/env bash
# The README's report picture (docs/images/report.png): `visage run --report` on the sample clip
# and the page in headless Chromium, 1400 px wide, its first 2,400 px (summary, viewer, warnings,
# the moments and the first curves).
#   scripts/dev/report_screenshot.sh [CLIP]   (default: ../shared/data/video/lp_d18.mp4)
set -euo pipefail
cd "$(dirname "$0")/../.."
clip="${1:-../shared/data/video/lp_d18.mp4}"
cargo build -q --release -p visage-cli
out=target/report-screenshot
target/release/visage run "$clip" --out "$out" --report --overwrite > /dev/null
chromium --headless --no-sandbox --disable-gpu --hide-scrollbars \
  --virtual-time-budget=3000 --window-size=1400,2400 \
  --screenshot=docs/images/report.png "file://$PWD/$out/report.html" 2> /dev/null
echo "report_screenshot: docs/images/report.png from $out/report.html"
