"""Fixtures of the cross-master tests (tests/interop).

Nothing is built here: run `cargo run --release -p fmu-build` first (the
FMU is <repo>/target/fmu/tdvass.fmu, or $TDVASS_FMU). The fmpy reference
runs are computed once per session and shared by every master's tests; an
agreement table is printed at the end (and written to
target/interop/summary.json).
"""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

import interop  # noqa: E402


@pytest.fixture(scope="session")
def fmu_file() -> Path:
    path = interop.fmu_path()
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


def pytest_terminal_summary(terminalreporter):
    lines = interop.summary_lines()
    if lines:
        terminalreporter.section("cross-master agreement (max relative difference over all outputs and points)")
        for line in lines:
            terminalreporter.write_line(line)
    interop.write_summary()
