#!/usr/bin/env bash
# Two builds of the same sources give byte-identical FMUs.
#
# Builds the FMUs again with `fmu-build --all-platforms`, from a copy of the
# sources at another path into a fresh target directory (so that neither the
# checkout's location nor anything left in target/ can reach the bytes), and
# compares them with <target>/fmu/tdvass.fmu, tdvass-fmi3.fmu,
# tdvass-corner.fmu, tdvass-corner-fmi3.fmu, tdvass-chassis.fmu,
# tdvass-chassis-fmi3.fmu and full-car.ssp, and the FMI 2.0 aarch64
# library, byte for byte. Run it after
# `cargo run --release -p fmu-build -- --all-platforms`; a difference names
# the archive entries that differ. Takes a few minutes (every platform's
# libraries are built from scratch).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
target="${CARGO_TARGET_DIR:-$root/target}"
case "$target" in /*) ;; *) target="$root/$target" ;; esac
first=("$target/fmu/tdvass.fmu" "$target/fmu/tdvass-fmi3.fmu"
    "$target/fmu/tdvass-corner.fmu" "$target/fmu/tdvass-corner-fmi3.fmu"
    "$target/fmu/tdvass-chassis.fmu" "$target/fmu/tdvass-chassis-fmi3.fmu"
    "$target/fmu/full-car.ssp"
    "$target/aarch64-unknown-linux-gnu/release/libtdvass_fmi2.so")
for file in "${first[@]}"; do
    [ -f "$file" ] || {
        echo "$file not found: build it first with cargo run --release -p fmu-build -- --all-platforms" >&2
        exit 1
    }
done
work="$(mktemp -d "${TMPDIR:-/tmp}/tdvass-reproducible.XXXXXX")"
trap 'rm -rf "$work"' EXIT
mkdir "$work/src"
# The files of the repository (tracked, and new ones not ignored), not
# target/ or .venv/; the copy uses this checkout's Python environment.
(cd "$root" && git ls-files -z --cached --others --exclude-standard | tar --null -T - -cf -) |
    tar -xf - -C "$work/src"
ln -s "$root/.venv" "$work/src/.venv"
echo "reproducible_fmus: building the FMUs again in $work" >&2
(cd "$work/src" && CARGO_TARGET_DIR="$work/target" cargo run --release -p fmu-build -- --all-platforms) \
    >"$work/build.log" 2>&1 || {
    tail -n 40 "$work/build.log" >&2
    exit 1
}
second=("$work/target/fmu/tdvass.fmu" "$work/target/fmu/tdvass-fmi3.fmu"
    "$work/target/fmu/tdvass-corner.fmu" "$work/target/fmu/tdvass-corner-fmi3.fmu"
    "$work/target/fmu/tdvass-chassis.fmu" "$work/target/fmu/tdvass-chassis-fmi3.fmu"
    "$work/target/fmu/full-car.ssp"
    "$work/target/aarch64-unknown-linux-gnu/release/libtdvass_fmi2.so")
failed=0
for i in "${!first[@]}"; do
    name="${first[$i]#"$target"/}"
    if cmp -s "${first[$i]}" "${second[$i]}"; then
        echo "reproducible_fmus: $name: byte-identical ($(wc -c <"${first[$i]}") bytes, sha256 $(sha256sum "${first[$i]}" | cut -c1-16)...)"
    else
        failed=1
        echo "reproducible_fmus: $name differs between the two builds" >&2
        case "$name" in
            *.fmu | *.ssp)
                python3 - "${first[$i]}" "${second[$i]}" <<'EOF' >&2
import sys, zipfile
a, b = (zipfile.ZipFile(p) for p in sys.argv[1:3])
if a.namelist() != b.namelist():
    print(f"  entries: {a.namelist()} against {b.namelist()}")
for name in a.namelist():
    if name in b.namelist() and a.read(name) != b.read(name):
        print(f"  {name} differs")
EOF
                ;;
        esac
    fi
done
exit "$failed"
