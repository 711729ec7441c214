#!/usr/bin/env bash
# Builds target/fmu/tdvass.fmu and runs its default experiment (TDVASS on
# the harmonic road, 15 s) through fmpy, printing the Table 2 TDVASS row.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
python="$(tests/python_env.sh)"
cargo run --quiet --release -p fmu-build
"$python" examples/default_experiment.py target/fmu/tdvass.fmu
