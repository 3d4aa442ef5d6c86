#!/usr/bin/env bash
# Dev-only: visage's SIFT against OpenCV's (scripts/dev/compare_sift.py; its docstring has the
# definitions). Makes a venv in target/dev-venv with pinned packages on first use, then runs it:
#   scripts/dev/compare_sift.sh              needs target/release/visage (cargo build --release)
#   scripts/dev/compare_sift.sh --self-test  OpenCV in visage's place, to check the metrics
# Other flags (--images, --quick, --margin, --repeat, --bin) go to the Python script.
set -euo pipefail
cd "$(dirname "$0")/../.."
venv=target/dev-venv
pins=(opencv-python-headless==4.10.0.84 scikit-image==0.25.2 numpy==2.2.6)
stamp="$venv/.compare_sift-pins"
if [ "$(cat "$stamp" 2>/dev/null)" != "${pins[*]}" ]; then
  echo "compare_sift: installing ${pins[*]} into $venv" >&2
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q --disable-pip-version-check "${pins[@]}"
  echo "${pins[*]}" > "$stamp"
fi
exec "$venv/bin/python" scripts/dev/compare_sift.py "$@"
