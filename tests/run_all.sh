#!/usr/bin/env bash
# Every test of the project: formatting, lints, Rust unit and integration
# tests, the FMU build and its freshness check, the fmpy suite and the
# cross-master interoperability tests.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
python="$(tests/python_env.sh)"
echo "== cargo fmt --check"
cargo fmt --all -- --check
echo "== cargo clippy"
cargo clippy --workspace --all-targets -- -D warnings
echo "== cargo test"
cargo test --workspace --release
echo "== fmu-build (the checked-in modelDescription must be current, then build the FMU)"
cargo run --release -p fmu-build -- --check
cargo run --release -p fmu-build -- --all-platforms
echo "== pytest (fmpy suite and examples)"
cargo build --release --bin tdvass
"$python" -m pytest tests/python -q
"$python" benches/peers.py --smoke  # peers of BENCHMARKS.md: smoke size, no timing claims
echo "== robustness suite against the built FMU (bad input, state table, divergence, hangs, valgrind, threads)"
"$python" -m pytest tests/robustness -q
echo "== platforms (the same harness on linux64 natively, win64 under wine, aarch64 under qemu)"
"$python" -m pytest tests/platforms -q
echo "== fuzzing smoke run (libFuzzer on stable, ${TDVASS_FUZZ_SECONDS:=60} s per target, both at once)"
bash fuzz/run.sh build
logs="$(mktemp -d)"
pids=()
for target in deserialize api_sequence; do
    bash fuzz/run.sh "$target" "$TDVASS_FUZZ_SECONDS" >"$logs/$target.log" 2>&1 &
    pids+=("$!")
done
failed=0
for i in 0 1; do
    target=$([ "$i" = 0 ] && echo deserialize || echo api_sequence)
    if wait "${pids[$i]}"; then
        grep -E "^(== |Done |stat::number_of_executed_units|stat::average_exec_per_sec)" "$logs/$target.log"
    else
        echo "fuzz target $target failed:"; tail -n 80 "$logs/$target.log"; failed=1
    fi
done
[ "$failed" = 0 ]
echo "== interop (fmpy API and CLI, libcosim, ecos, fmutool -check, Rust fmi crate)"
# tests/interop/test_fmi_rs.py takes the interop-fmi-rs executable that the
# cargo test step built (its CARGO_TEST repeats that step's flags).
"$python" -m pytest tests/interop -q
