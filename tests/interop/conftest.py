"""Fixtures of the cross-master tests (tests/interop).

Nothing is built here: run `cargo run --release -p fmu-build` first (the
FMU is <repo>/target/fmu/tdvass.fmu, or $TDVASS_FMU). The fmpy reference
runs are computed once per session and shared by every master's tests; an
agreement table is printed at the end (and written to
target/interop/summary.json).
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

import interop  # noqa: E402
from interop import REPO_ROOT  # noqa: E402

FMI_CRATE = "0.8.0"  # pinned in interop-fmi-rs/Cargo.toml
CARGO_TEST = ["cargo", "test", "--workspace", "--release"]  # as in tests/run_all.sh


@pytest.fixture(scope="session")
def fmu_file() -> Path:
    path = interop.fmu_path()
    if not path.is_file():
        pytest.fail(f"{path} not found; build it with `cargo run --release -p fmu-build`")
    return path


@pytest.fixture(params=sorted(interop.CORNER_FMUS))
def corner_file(request) -> Path:
    """Each of the corner's FMUs, by file name."""
    path = interop.fmu_path().with_name(request.param)
    if not path.is_file():
        pytest.fail(f"{path} not found; build it with `cargo run --release -p fmu-build`")
    return path


@pytest.fixture(params=sorted(interop.CHASSIS_FMUS))
def chassis_file(request) -> Path:
    """Each of the chassis's FMUs, by file name."""
    path = interop.fmu_path().with_name(request.param)
    if not path.is_file():
        pytest.fail(f"{path} not found; build it with `cargo run --release -p fmu-build`")
    return path


@pytest.fixture(scope="session")
def fmpy_reference(fmu_file):
    """fmpy.simulate_fmu of each experiment: name -> (times, rows), memoized."""
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = interop.simulate_fmu(fmu_file, interop.EXPERIMENTS[name])
        return cache[name]

    return get


@pytest.fixture(scope="session")
def replay(fmu_file):
    """fmpy's FMU2Slave through given communication times, memoized by experiment and times."""
    cache = {}

    def get(name, times):
        key = (name, np.asarray(times, dtype=float).tobytes())
        if key not in cache:
            cache[key] = interop.replay(fmu_file, interop.EXPERIMENTS[name], times)
        return cache[key]

    return get


@pytest.fixture(scope="session")
def grid_reference(fmu_file, fmpy_reference):
    """fmpy on its grid (k * h) with the outputs' rates, for a master's
    times (which feed the road of the input-road experiment):
    (times, rows, rates). The rows equal fmpy.simulate_fmu's for the
    built-in roads (checked)."""

    def get(name, master_times):
        experiment = interop.EXPERIMENTS[name]
        times, rows, rates = interop.grid_reference(fmu_file, experiment, master_times)
        if experiment.source is None:
            fmpy_times, reference = fmpy_reference(name)
            np.testing.assert_array_equal(times, fmpy_times)
            np.testing.assert_array_equal(rows, reference)
        return times, rows, rates

    return get


@pytest.fixture(scope="session")
def fmi_rs():
    """The interop-fmi-rs executable: $TDVASS_INTEROP_FMI_RS, or cargo's.

    The `cargo test --workspace --release` step of tests/run_all.sh builds
    it for the crate's integration test; asking the same command for its
    artifacts rebuilds nothing, where `cargo build -p interop-fmi-rs` would
    resolve the dependencies' features differently and recompile some.
    Keep CARGO_TEST in step with run_all.sh.
    """
    override = os.environ.get("TDVASS_INTEROP_FMI_RS")
    if override:
        return override
    done = subprocess.run(
        CARGO_TEST + ["--no-run", "--message-format=json-render-diagnostics"],
        cwd=REPO_ROOT, capture_output=True, text=True,
    )
    assert done.returncode == 0, done.stderr
    for line in done.stdout.splitlines():
        message = json.loads(line)
        if (message.get("reason") == "compiler-artifact" and message["target"]["name"] == "interop-fmi-rs"
                and message["target"]["kind"] == ["bin"] and not message["profile"]["test"]):
            return message["executable"]
    pytest.fail("cargo built no interop-fmi-rs executable")


def pytest_terminal_summary(terminalreporter):
    lines = interop.summary_lines()
    if lines:
        terminalreporter.section("cross-master agreement (max relative difference over all outputs and points)")
        for line in lines:
            terminalreporter.write_line(line)
    interop.write_summary()
