#!/usr/bin/env bash
# Creates (once) the Python environment at .venv and prints the path of its
# python.
#
#   tests/python_env.sh             the full set of tests/run_all.sh
#                                   (tests/python/requirements.txt: pytest,
#                                   dask, the interop masters, the peers of
#                                   the benchmarks, ...)
#   tests/python_env.sh quickstart  the small set of examples/quickstart.sh
#                                   (examples/requirements.txt: fmpy, numpy,
#                                   matplotlib)
#   tests/python_env.sh build       the linker of `fmu-build --all-platforms`
#                                   (fmu-build/requirements.txt: zig and
#                                   cargo-zigbuild, for the glibc 2.17 floor
#                                   of the Linux libraries)
#
# The full set contains the other two, so a full environment also serves
# the quick start and the build.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="$root/.venv"
quickstart="$root/examples/requirements.txt"
build="$root/fmu-build/requirements.txt"
full="$root/tests/python/requirements.txt"
full_files=("$full" "$quickstart" "$build")
set_name="${1:-full}"
case "$set_name" in
    quickstart) files=("$quickstart") ;;
    build) files=("$build") ;;
    full) files=("${full_files[@]}") ;;
    *)
        echo "usage: tests/python_env.sh [quickstart|build|full]" >&2
        exit 2
        ;;
esac
# Each set's stamp holds the requirement files it was installed from.
wanted="$(cat "${files[@]}")"
installed() { # installed SET CONTENT
    [ -x "$venv/bin/python" ] && [ -f "$venv/.requirements-$1" ] &&
        [ "$(cat "$venv/.requirements-$1")" = "$2" ]
}
if ! installed "$set_name" "$wanted" && ! installed full "$(cat "${full_files[@]}")"; then
    echo "installing the $set_name Python set (${files[0]#"$root"/}) into $venv" >&2
    python3 -m venv "$venv" >&2
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r "${files[0]}" >&2
    printf '%s' "$wanted" >"$venv/.requirements-$set_name"
fi
echo "$venv/bin/python"
