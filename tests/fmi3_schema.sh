#!/usr/bin/env bash
# Validates the FMI 3.0 model descriptions against the official XML schema
# of the standard (modelica/fmi-standard, release v3.0.2) with xmllint.
#
#   tests/fmi3_schema.sh            the checked-in modelDescription/fmi3/modelDescription.xml,
#                                   modelDescription/corner/fmi3/modelDescription.xml
#                                   and modelDescription/chassis/fmi3/modelDescription.xml
#                                   and, when they were built, the ones inside
#                                   target/fmu/tdvass-fmi3.fmu, tdvass-corner-fmi3.fmu
#                                   and tdvass-chassis-fmi3.fmu
#   tests/fmi3_schema.sh FILE...    these files
#
# The schema is taken from FMI3_SCHEMA_DIR (a directory holding
# fmi3ModelDescription.xsd and the files it includes) or, without it, from
# the copy of the standard's schema that fmpy ships (fmpy/schema/fmi3) in
# the test environment of tests/python_env.sh. Needs xmllint (Debian:
# libxml2-utils).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
if ! command -v xmllint >/dev/null; then
    echo "tests/fmi3_schema.sh needs xmllint: apt-get install libxml2-utils" >&2
    exit 1
fi
target="${CARGO_TARGET_DIR:-target}"
case "$target" in /*) ;; *) target="$root/$target" ;; esac
if [ -n "${FMI3_SCHEMA_DIR:-}" ]; then
    schema_dir="$FMI3_SCHEMA_DIR"
else
    python="$(tests/python_env.sh)"
    schema_dir="$("$python" -c 'import os, fmpy; print(os.path.join(os.path.dirname(fmpy.__file__), "schema", "fmi3"))')"
fi
schema="$schema_dir/fmi3ModelDescription.xsd"
if [ ! -f "$schema" ]; then
    echo "no fmi3ModelDescription.xsd in $schema_dir" >&2
    exit 1
fi
files=("$@")
scratch=""
if [ ${#files[@]} -eq 0 ]; then
    files=(modelDescription/fmi3/modelDescription.xml modelDescription/corner/fmi3/modelDescription.xml
        modelDescription/chassis/fmi3/modelDescription.xml)
    scratch="$(mktemp -d)"
    trap 'rm -rf "$scratch"' EXIT
    for name in tdvass-fmi3 tdvass-corner-fmi3 tdvass-chassis-fmi3; do
        fmu="$target/fmu/$name.fmu"
        if [ -f "$fmu" ]; then
            python3 -c 'import sys, zipfile; sys.stdout.buffer.write(zipfile.ZipFile(sys.argv[1]).read("modelDescription.xml"))' \
                "$fmu" >"$scratch/$name.xml"
            files+=("$scratch/$name.xml")
        fi
    done
fi
xmllint --noout --schema "$schema" "${files[@]}"
