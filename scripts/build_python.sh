#!/usr/bin/env bash
# Builds the Python package's wheel (python/, with the model files scripts/setup.sh copied into
# it) with maturin and installs it into the virtual environment scripts/setup.sh made.
#
#   scripts/build_python.sh release   optimised and stripped (what a user installs)
#   scripts/build_python.sh dev       the test build's profile, which shares the compiled
#                                     dependencies of `cargo test` (scripts/test.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
profile="${1:-release}"
target_dir="$(realpath -m "${CARGO_TARGET_DIR:-target}")"
py_venv="$target_dir/py-venv"
if [ ! -x "$py_venv/bin/maturin" ]; then
  echo "build_python: no $py_venv/bin/maturin: run scripts/setup.sh first" >&2
  exit 1
fi
wheels="$target_dir/wheels/$profile"
rm -rf "$wheels"
(cd python && "$py_venv/bin/maturin" build -q --profile "$profile" --strip -o "$wheels")
"$py_venv/bin/pip" install -q --force-reinstall --no-deps "$wheels"/visage-*.whl
