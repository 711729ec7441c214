#!/usr/bin/env bash
# Builds the command line tool (target/release/tdvass) and the FMUs
# (target/fmu/tdvass.fmu, FMI 2.0, and target/fmu/tdvass-fmi3.fmu, FMI 3.0),
# then runs the FMI 2.0 FMU's default experiment (TDVASS on
# the harmonic road, 15 s) through fmpy, printing the Table 2 TDVASS row.
# Python: the small quick-start set (fmpy, numpy, matplotlib) in .venv.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
python="$(tests/python_env.sh quickstart)"
echo "== building the command line tool (target/release/tdvass)"
cargo build --release -p tdvass-cli --bin tdvass
echo "== building the FMUs (target/fmu/tdvass.fmu, target/fmu/tdvass-fmi3.fmu)"
# Without the profile-guided optimization of the release build
# (fmu-build/src/pgo.rs): the same results, about a minute and a half less on two cores.
cargo run --release -p fmu-build -- --no-profile
echo "== the FMU's default experiment through fmpy"
"$python" examples/default_experiment.py target/fmu/tdvass.fmu
echo
echo "Next: target/release/tdvass --help, the examples in examples/README.md (their"
echo "Python: $python), and examples/plot_result.py to plot a run."
