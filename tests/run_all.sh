#!/usr/bin/env bash
# Every test of the project: formatting, lints, Rust unit and integration
# tests, the FMU build (every platform) and its freshness check, the fmpy
# suite, robustness, the platform harness and the glibc policy, a second
# build that must give the same FMUs, fuzzing and the cross-master
# interoperability tests.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
# What the tests need besides Rust and Python 3 (the same list as .ci/run,
# which installs it): checked up front, so that a missing package stops
# here with the command that installs it rather than deep inside a phase.
missing=()
python3 -c "import venv, ensurepip" 2>/dev/null || missing+=(python3-venv)
if command -v dpkg-query >/dev/null; then
    for package in libtbb12 libclang-dev valgrind gcc g++ libxml2-utils \
        gcc-mingw-w64-x86-64 gcc-aarch64-linux-gnu libc6-dev-arm64-cross wine64 qemu-user; do
        dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" ||
            missing+=("$package")
    done
else
    echo "note: no dpkg-query; make sure libtbb12, libclang-dev, valgrind, gcc, g++, xmllint, the MinGW-w64 and aarch64 cross compilers, wine64 and qemu-user (or your system's equivalents) are installed" >&2
fi
if [ ${#missing[@]} -gt 0 ]; then
    echo "tests/run_all.sh needs these Debian packages: ${missing[*]}" >&2
    echo "install them with:  apt-get install -y --no-install-recommends ${missing[*]}" >&2
    echo "(or run .ci/run, which installs them and then runs this script)" >&2
    exit 1
fi
if ! cargo fmt --version >/dev/null 2>&1 || ! cargo clippy --version >/dev/null 2>&1; then
    echo "tests/run_all.sh needs rustfmt and clippy: rustup component add rustfmt clippy" >&2
    exit 1
fi
for target in x86_64-pc-windows-gnu aarch64-unknown-linux-gnu; do
    if ! rustup target list --installed 2>/dev/null | grep -qx "$target"; then
        echo "tests/run_all.sh needs the Rust target $target: rustup target add $target" >&2
        exit 1
    fi
done
# zig, through cargo-zigbuild, links the Linux libraries of `fmu-build
# --all-platforms` against glibc 2.17: both from PyPI into .venv (or both on
# the PATH), as fmu-build looks for them.
if ! { [ -x .venv/bin/cargo-zigbuild ] && .venv/bin/python -m ziglang version >/dev/null 2>&1; } &&
    ! { command -v cargo-zigbuild >/dev/null && command -v zig >/dev/null; }; then
    echo "tests/run_all.sh needs zig and cargo-zigbuild, the linker of the glibc 2.17 Linux libraries" >&2
    echo "install them into .venv with:  tests/python_env.sh build   (fmu-build/requirements.txt)" >&2
    exit 1
fi
python="$(tests/python_env.sh)"
echo "== cargo fmt --check"
cargo fmt --all -- --check
echo "== cargo clippy"
cargo clippy --workspace --all-targets -- -D warnings
echo "== cargo test"
cargo test --workspace --release
echo "== fmu-build (the checked-in model descriptions must be current, then build both FMUs)"
cargo run --release -p fmu-build -- --check
cargo run --release -p fmu-build -- --all-platforms
echo "== the FMI 3.0 model descriptions against the schema of the standard (xmllint)"
bash tests/fmi3_schema.sh
echo "== pytest (fmpy suite and examples)"
cargo build --release --bin tdvass
"$python" -m pytest tests/python -q
"$python" benches/peers.py --smoke  # peers of BENCHMARKS.md: smoke size, no timing claims
echo "== robustness suite against the built FMU (bad input, state table, divergence, hangs, valgrind, threads)"
"$python" -m pytest tests/robustness -q
echo "== platforms (the same harness on linux64 natively, win64 under wine, aarch64 under qemu; the glibc 2.17 policy of the Linux libraries)"
"$python" -m pytest tests/platforms -q
echo "== reproducible FMUs (both FMUs built again from a copy of the sources into a fresh target directory: byte-identical)"
bash tests/reproducible_fmus.sh
echo "== fuzzing smoke run (libFuzzer on stable, ${TDVASS_FUZZ_SECONDS:=60} s on each of the two cores: api_sequence_fmi3 on one, deserialize then api_sequence for half of it each on the other)"
bash fuzz/run.sh build
logs="$(mktemp -d)"
half=$(( (TDVASS_FUZZ_SECONDS + 1) / 2 ))
bash fuzz/run.sh api_sequence_fmi3 "$TDVASS_FUZZ_SECONDS" >"$logs/api_sequence_fmi3.log" 2>&1 &
fmi3_pid=$!
(
    bash fuzz/run.sh deserialize "$half" >"$logs/deserialize.log" 2>&1 &&
        bash fuzz/run.sh api_sequence "$half" >"$logs/api_sequence.log" 2>&1
) &
fmi2_pid=$!
failed=0
wait "$fmi3_pid" || failed=1
wait "$fmi2_pid" || failed=1
for target in deserialize api_sequence api_sequence_fmi3; do
    if [ -f "$logs/$target.log" ] && grep -q "^Done " "$logs/$target.log"; then
        grep -E "^(== |Done |stat::number_of_executed_units|stat::average_exec_per_sec)" "$logs/$target.log"
    else
        echo "fuzz target $target failed:"; tail -n 80 "$logs/$target.log" 2>/dev/null || echo "(not run)"; failed=1
    fi
done
[ "$failed" = 0 ]
echo "== interop (fmpy API and CLI, libcosim, ecos, fmutool -check, Rust fmi crate; fmi-sim when installed)"
# tests/interop/test_fmi_rs.py takes the interop-fmi-rs executable that the
# cargo test step built (its CARGO_TEST repeats that step's flags).
"$python" -m pytest tests/interop -q
