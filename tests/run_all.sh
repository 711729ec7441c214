#!/usr/bin/env bash
# Every test of the project: formatting, lints, Rust unit and integration
# tests, the FMU build and its freshness check, and the fmpy suite.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
python="$(tests/python_env.sh)"
echo "== cargo fmt --check"
cargo fmt --all -- --check
echo "== cargo clippy"
cargo clippy --workspace --all-targets -- -D warnings
echo "== cargo test"
cargo test --workspace
echo "== fmu-build (the checked-in modelDescription must be current, then build the FMU)"
cargo run --release -p fmu-build -- --check
cargo run --release -p fmu-build
echo "== pytest (fmpy suite and examples)"
cargo build --release --bin tdvass
"$python" -m pytest tests/python -q
