#!/usr/bin/env bash
# The project's test command: formatting, lints, import circles, the whole test suite (unit,
# integration and doc tests) and the docs.
# Tests that need ../shared (data, reference outputs), the model files, FFmpeg or the web tools
# (web/viewer built, Chromium) are listed as *ignored* when those are absent (run
# scripts/setup.sh first); with CI=true they run and fail.
set -euo pipefail
cd "$(dirname "$0")/.."
# What is present, so that the tests' build scripts re-run when it changes (crates/testdata).
models="${VISAGE_MODELS:-models}"
VISAGE_TEST_DATA="shared=$([ -d ../shared/data ] && echo 1 || echo 0)"
VISAGE_TEST_DATA+=" models=$(ls "$models" 2>/dev/null | tr '\n' ,)"
VISAGE_TEST_DATA+=" ffmpeg=$(command -v ffmpeg >/dev/null && echo 1 || echo 0)"
VISAGE_TEST_DATA+=" chromium=$([ -x /usr/bin/chromium ] && echo 1 || echo 0)"
VISAGE_TEST_DATA+=" validator=$([ -d web/viewer/node_modules/gltf-validator ] && echo 1 || echo 0)"
export VISAGE_TEST_DATA
# Each step's end, in seconds since the start: where the suite's time goes.
step() { echo "test: $1 done at ${SECONDS} s" >&2; }
cargo fmt --all --check
cargo clippy -q --workspace --all-targets -- -D warnings
step clippy
python3 scripts/import_cycles.py
cargo test --workspace
step "cargo test"
# The Python package: its wheel built with the test build's profile (the dependencies `cargo
# test` compiled), installed in target/py-venv, and its tests (pytest) against the command
# line's debug binary.
py_venv="${CARGO_TARGET_DIR:-target}/py-venv"
if [ -x "$py_venv/bin/maturin" ]; then
  bash scripts/build_python.sh dev
  VISAGE_BIN="${CARGO_TARGET_DIR:-target}/debug/visage" "$py_venv/bin/python" -m pytest -q python/tests
  step "Python package"
elif [ "${CI:-}" = true ]; then
  echo "test: no $py_venv/bin/maturin for the Python package (scripts/setup.sh)" >&2
  exit 1
else
  echo "test: skipped the Python package (no $py_venv: run scripts/setup.sh)" >&2
fi
# The batch deploy files: the Kubernetes manifest against the schemas, the Slurm array job on
# a single-node cluster started for the test (each says why when it skips).
bash scripts/test_deploy.sh
bash scripts/test_slurm.sh "${CARGO_TARGET_DIR:-target}/debug/visage"
step "deploy and Slurm"
RUSTDOCFLAGS="-D warnings" cargo doc -q --workspace --no-deps
step docs
# The fuzz targets: their bodies (crates/fuzz-targets) are replayed above, by `cargo test`, on
# their seeds and 20,000 deterministic mutants each; their cargo-fuzz wrappers (fuzz/, a
# workspace of its own that `cargo +nightly fuzz` runs; see fuzz/README.md) must keep
# compiling: formatted and type-checked on this toolchain, without building libFuzzer's C++
# runtime (--no-default-features), in fuzz/target.
cargo fmt --manifest-path fuzz/Cargo.toml --check
cargo check -q --manifest-path fuzz/Cargo.toml --no-default-features
step "fuzz wrappers"
