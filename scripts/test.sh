#!/usr/bin/env bash
# The project's test command: formatting, lints, the whole test suite and the docs.
# Tests that need ../shared (data, reference outputs) or the model files say SKIPPED when
# those are absent; run scripts/setup.sh first to fetch the models.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo fmt --all --check
cargo clippy -q --workspace --all-targets -- -D warnings
cargo test --workspace
RUSTDOCFLAGS="-D warnings" cargo doc -q --workspace --no-deps
