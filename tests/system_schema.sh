#!/usr/bin/env bash
# Validates the full car's system-structure files that fmu-build writes
# beside the FMUs against their publishers' XML schemas with xmllint.
#
#   tests/system_schema.sh          SystemStructure.ssd inside target/fmu/full-car.ssp
#                                   against SSP 1.0.1's SSD schema, its
#                                   ssv:ParameterSets included, and
#                                   target/fmu/full-car/OspSystemStructure.xml and
#                                   OspSystemStructure_ecco.xml against libcosim's
#                                   OspSystemStructure.xsd
#   tests/system_schema.sh FILE...  these files: *.ssp (its SystemStructure.ssd)
#                                   and *.ssd as SSDs, anything else as an OSP
#                                   system structure
#
# The schemas are vendored, unmodified, under tests/schemas/ (sources,
# versions and licenses: tests/schemas/README.md). The SSD schema admits
# the content of ssd:ParameterValues as a lax wildcard, which xmllint checks
# only against a schema it has loaded for that namespace; the SSD is
# therefore validated against tests/schemas/system-structure.xsd, which
# imports the SSD schema together with the parameter values' schema. After
# the files validate, the script makes sure the checks can fail: a copy of
# an SSD whose ssv:Real values lost their required attribute, and of an ECCO
# structure without its SafetyFactor, must be refused. Needs xmllint (Debian:
# libxml2-utils) and python3 (to read the .ssp archive).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
if ! command -v xmllint >/dev/null; then
    echo "tests/system_schema.sh needs xmllint: apt-get install libxml2-utils" >&2
    exit 1
fi
target="${CARGO_TARGET_DIR:-target}"
case "$target" in /*) ;; *) target="$root/$target" ;; esac
ssd_schema="$root/tests/schemas/system-structure.xsd"
osp_schema="$root/tests/schemas/osp/OspSystemStructure.xsd"
build_hint="build it with \`cargo run --release -p fmu-build\`"

scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT

ssds=()
osps=()
add_ssp() { # add_ssp ARCHIVE: its SystemStructure.ssd
    local out
    out="$scratch/${#ssds[@]}/$(basename "$1")/SystemStructure.ssd"
    mkdir -p "$(dirname "$out")"
    python3 -c 'import sys, zipfile; sys.stdout.buffer.write(zipfile.ZipFile(sys.argv[1]).read("SystemStructure.ssd"))' \
        "$1" >"$out"
    ssds+=("$out")
}
if [ $# -eq 0 ]; then
    for file in "$target/fmu/full-car.ssp" "$target/fmu/full-car/OspSystemStructure.xml" \
        "$target/fmu/full-car/OspSystemStructure_ecco.xml"; do
        if [ ! -f "$file" ]; then
            echo "$file not found; $build_hint" >&2
            exit 1
        fi
    done
    add_ssp "$target/fmu/full-car.ssp"
    osps=("$target/fmu/full-car/OspSystemStructure.xml" "$target/fmu/full-car/OspSystemStructure_ecco.xml")
else
    for file in "$@"; do
        case "$file" in
            *.ssp) add_ssp "$file" ;;
            *.ssd) ssds+=("$file") ;;
            *) osps+=("$file") ;;
        esac
    done
fi

status=0
if [ ${#ssds[@]} -gt 0 ]; then
    xmllint --noout --schema "$ssd_schema" "${ssds[@]}" || status=1
fi
if [ ${#osps[@]} -gt 0 ]; then
    xmllint --noout --schema "$osp_schema" "${osps[@]}" || status=1
fi
[ $status -eq 0 ] || exit $status

# The checks can fail: a broken copy of each valid file must be refused.
refused() { # refused SCHEMA FILE WHAT
    if xmllint --noout --schema "$1" "$2" >"$scratch/refusal.log" 2>&1; then
        echo "tests/system_schema.sh: $3 passed $(basename "$1"); the check does not reach it" >&2
        exit 1
    fi
}
for file in "${ssds[@]}"; do
    if grep -q '<ssv:Real value=' "$file"; then
        sed 's/<ssv:Real value=/<ssv:Real amount=/' "$file" >"$scratch/broken.ssd"
        refused "$ssd_schema" "$scratch/broken.ssd" "an ssv:Real without its value"
    elif [ $# -eq 0 ]; then
        echo "tests/system_schema.sh: no ssv:Real in the full car's SSD; its parameter sets went unchecked" >&2
        exit 1
    fi
done
for file in "${osps[@]}"; do
    if grep -q '<SafetyFactor>' "$file"; then
        sed 's|<SafetyFactor>[^<]*</SafetyFactor>||' "$file" >"$scratch/broken.xml"
        refused "$osp_schema" "$scratch/broken.xml" "an EccoConfiguration without SafetyFactor"
    fi
done
echo "tests/system_schema.sh: ${#ssds[@]} SSD and ${#osps[@]} OSP files valid; broken copies refused"
