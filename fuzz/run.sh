#!/usr/bin/env bash
# Fuzzes one target, or every target in turn, with the settings of fuzz/README.md's results:
# the committed seeds (seeds/<target>/) copied into the git-ignored corpus (corpus/<target>/,
# which libFuzzer grows), one process, the target's maximum input length, a 2 GB memory limit,
# 10 s per input, at most RUNS executions (default 1,000,000) or 30 minutes.
#
#   fuzz/run.sh TARGET [RUNS] [more libFuzzer flags…]
#   fuzz/run.sh all [RUNS]
#
# Needs the nightly toolchain and cargo-fuzz (`cargo install cargo-fuzz --locked`). The targets
# are built once (`cargo +nightly fuzz build`: release, debug assertions, AddressSanitizer), then
# run directly, as `cargo fuzz run` would. Crashes, leaks and timeouts land in
# artifacts/<target>/; `cargo +nightly fuzz tmin TARGET FILE` minimises one.
set -euo pipefail
cd "$(dirname "$0")"

# Longest input libFuzzer makes per target (bytes): a few times the largest seed.
max_len() {
    case "$1" in
        exif) echo 512 ;;
        keypoints_json) echo 4096 ;;
        intrinsics_json | rigid_transform_json | pc2 | network_config) echo 1024 ;;
        tum_list | batch_manifest | streamed_records) echo 4096 ;;
        obj | ply | canonical_mesh) echo 4096 ;;
        depth_png | tflite | image) echo 8192 ;;
        *) echo "unknown fuzz target $1" >&2; exit 2 ;;
    esac
}

target=${1:?usage: fuzz/run.sh TARGET|all [RUNS] [libFuzzer flags…]}
runs=${2:-1000000}
shift $(($# < 2 ? $# : 2))
if [ "$target" = all ]; then
    targets=$(cargo +nightly fuzz list)
else
    max_len "$target" >/dev/null
    targets=$target
fi
cargo +nightly fuzz build
bin="target/$(rustc +nightly -vV | sed -n 's/^host: //p')/release"
for t in $targets; do
    mkdir -p "corpus/$t" "artifacts/$t"
    cp seeds/"$t"/* "corpus/$t/"
    "$bin/$t" -artifact_prefix="artifacts/$t/" -runs="$runs" -max_total_time=1800 \
        -max_len="$(max_len "$t")" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 \
        "$@" "corpus/$t"
done
