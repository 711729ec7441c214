#!/usr/bin/env bash
# The test suite, in phases:
#
#   tests/run_all.sh                 every phase, in the order below
#   tests/run_all.sh PHASE...        the named phases only (each builds what it tests)
#   tests/run_all.sh --list          the phases, what they run and their measured times
#
# It first installs what the machine lacks (tests/setup.sh: Debian packages
# as root, Rust components and targets, the Python set in .venv) or, where
# it cannot, names the command that does. At the end it prints each phase's
# time; the times of the last full run on this machine are kept in
# target/run_all-times.tsv and shown by --list.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

# name | what it runs | minutes on two cores (measured from a fresh clone: docs/testing.md)
phases=(
    "rust|cargo fmt --check, clippy -D warnings, rustdoc -D warnings, cargo test (workspace, release)|9"
    "fmu|fmu-build --check (generated descriptions current), every platform's FMUs, the FMI 3.0 schema, the SSP and OSP schemas of the full car, a second build byte-identical|5"
    "python|the fmpy suite and the examples (tests/python), the peers' smoke run|2"
    "robustness|bad input, the state table, divergence, hangs, valgrind, threads (tests/robustness)|10"
    "platforms|one C harness on linux64, win64 under wine and aarch64 under qemu; the glibc 2.17 policy (tests/platforms)|1"
    "fuzz|libFuzzer smoke run of the three fuzz targets, TDVASS_FUZZ_SECONDS (60) on each core (fuzz/run.sh smoke)|3"
    "interop|other masters: fmpy CLI, libcosim, ecos, fmutool -check, the Rust fmi crate (tests/interop)|1"
)
times_file="${CARGO_TARGET_DIR:-target}/run_all-times.tsv"
[[ "$times_file" = /* ]] || times_file="$root/$times_file"

list_phases() {
    local entry name what minutes last
    printf '%-11s %-8s %-10s %s\n' phase measured "last here" "what it runs"
    for entry in "${phases[@]}"; do
        IFS='|' read -r name what minutes <<<"$entry"
        last="-"
        [ -f "$times_file" ] && last="$(awk -F'\t' -v p="$name" '$1 == p { print $2 " s" }' "$times_file")"
        printf '%-11s %-8s %-10s %s\n' "$name" "~$minutes min" "${last:--}" "$what"
    done
}

known() { # known NAME
    local entry
    for entry in "${phases[@]}"; do [ "${entry%%|*}" = "$1" ] && return 0; done
    return 1
}

selected=()
for argument in "$@"; do
    case "$argument" in
        --list) list_phases; exit 0 ;;
        -h | --help) sed -n '2,12p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *)
            if ! known "$argument"; then
                echo "tests/run_all.sh: unknown phase '$argument'; the phases are: $(for e in "${phases[@]}"; do printf '%s ' "${e%%|*}"; done)" >&2
                exit 2
            fi
            selected+=("$argument")
            ;;
    esac
done
if [ ${#selected[@]} -eq 0 ]; then
    for entry in "${phases[@]}"; do selected+=("${entry%%|*}"); done
fi

tests/setup.sh
python="$(tests/python_env.sh)"

fmus_built=false
build_fmus() { # every platform's FMUs and the CLI, once per run
    if ! $fmus_built; then
        echo "-- building the CLI and the FMUs of every platform"
        cargo build --release --bin tdvass
        cargo run --release -p fmu-build -- --all-platforms
        fmus_built=true
    fi
}

phase_rust() {
    cargo fmt --all -- --check
    cargo clippy --workspace --all-targets -- -D warnings
    RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --document-private-items --quiet
    cargo test --workspace --release
}

phase_fmu() {
    cargo run --release -p fmu-build -- --check
    build_fmus
    bash tests/fmi3_schema.sh
    bash tests/system_schema.sh
    bash tests/reproducible_fmus.sh
}

phase_python() {
    build_fmus
    "$python" -m pytest tests/python -q
    "$python" benches/peers.py --smoke # peers of BENCHMARKS.md: smoke size, no timing claims
}

phase_robustness() {
    build_fmus
    "$python" -m pytest tests/robustness -q
}

phase_platforms() {
    build_fmus
    "$python" -m pytest tests/platforms -q
}

phase_fuzz() {
    bash fuzz/run.sh smoke "${TDVASS_FUZZ_SECONDS:-60}"
}

phase_interop() {
    # tests/interop/test_fmi_rs.py asks `cargo test --workspace --release`
    # for the interop-fmi-rs executable (built by the rust phase, or now).
    build_fmus
    "$python" -m pytest tests/interop -q
}

timings=()
for name in "${selected[@]}"; do
    for entry in "${phases[@]}"; do
        [ "${entry%%|*}" = "$name" ] && echo "== $name: $(cut -d'|' -f2 <<<"$entry")"
    done
    started=$SECONDS
    "phase_$name"
    timings+=("$name"$'\t'"$((SECONDS - started))")
done

echo "== all selected phases passed: ${selected[*]}"
printf '%s\n' "${timings[@]}" | awk -F'\t' '{ printf "   %-11s %5d s\n", $1, $2 }'
if [ ${#selected[@]} -eq ${#phases[@]} ]; then
    mkdir -p "$(dirname "$times_file")"
    printf '%s\n' "${timings[@]}" >"$times_file"
fi
