#!/usr/bin/env bash
# Builds the fuzz targets with libFuzzer on the stable toolchain (plain
# cargo: SanitizerCoverage through stable -C flags, libFuzzer compiled by
# libfuzzer-sys with the system C++ compiler), replays the regression
# inputs, then fuzzes.
#
#   fuzz/run.sh TARGET SECONDS [libFuzzer flags...]   TARGET: deserialize | api_sequence | api_sequence_fmi3
#   fuzz/run.sh build                                  only build
#   fuzz/run.sh smoke SECONDS                          the suite's smoke run (tests/run_all.sh fuzz):
#       SECONDS on each of two cores, api_sequence_fmi3 on one, deserialize
#       then api_sequence for half of it each on the other; prints each
#       target's statistics, or its log's tail and a failure
#
# The corpus grows in fuzz/corpus/TARGET (only the checked-in seed-* files
# are versioned); crashing inputs land in fuzz/artifacts/TARGET/ — copy
# them to fuzz/regressions/TARGET/ to keep them as regression tests.
# `cargo fuzz run TARGET` (with RUSTC_BOOTSTRAP=1 -s none on stable) works too.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
export CARGO_TARGET_DIR="${FUZZ_TARGET_DIR:-$here/target}"
export RUSTFLAGS="--cfg fuzzing -Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 -Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table -Cllvm-args=-sanitizer-coverage-trace-compares -Cdebug-assertions -Coverflow-checks"
# With an explicit --target the flags reach the targets only, not build scripts.
triple="$(rustc -vV | sed -n 's/^host: //p')"
cargo build --release --bins --quiet --target "$triple"
[ "${1:-build}" = build ] && exit 0
if [ "$1" = smoke ]; then
    seconds="${2:-60}"
    half=$(((seconds + 1) / 2))
    logs="$(mktemp -d)"
    "$here/run.sh" api_sequence_fmi3 "$seconds" >"$logs/api_sequence_fmi3.log" 2>&1 &
    fmi3_pid=$!
    (
        "$here/run.sh" deserialize "$half" >"$logs/deserialize.log" 2>&1 &&
            "$here/run.sh" api_sequence "$half" >"$logs/api_sequence.log" 2>&1
    ) &
    fmi2_pid=$!
    failed=0
    wait "$fmi3_pid" || failed=1
    wait "$fmi2_pid" || failed=1
    for target in deserialize api_sequence api_sequence_fmi3; do
        if [ -f "$logs/$target.log" ] && grep -q "^Done " "$logs/$target.log"; then
            grep -E "^(== |Done |stat::number_of_executed_units|stat::average_exec_per_sec)" "$logs/$target.log"
        else
            echo "fuzz target $target failed:"
            tail -n 80 "$logs/$target.log" 2>/dev/null || echo "(not run)"
            failed=1
        fi
    done
    rm -rf "$logs"
    exit "$failed"
fi
target="$1"
seconds="${2:-60}"
shift 2 || shift $#
binary="$CARGO_TARGET_DIR/$triple/release/$target"
mkdir -p "corpus/$target" "artifacts/$target" "regressions/$target"
regressions=("regressions/$target"/*)
if [ -e "${regressions[0]}" ]; then
    echo "== $target: replaying ${#regressions[@]} regression input(s)"
    "$binary" -timeout=20 "${regressions[@]}"
fi
echo "== $target: fuzzing for $seconds s"
"$binary" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=4096 -max_len=32768 \
    -print_final_stats=1 -artifact_prefix="artifacts/$target/" "$@" \
    "corpus/$target" "regressions/$target"
