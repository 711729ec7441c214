"""libcosim (the Open Simulation Platform's co-simulation library) through
libcosimpy: fixed-step execution, parameters as initial values, a
time-series observer, and for the input road a connection between two
instances.

libcosim's clock is integer nanoseconds: the FMU is stepped to
t_k = (k * 1e6 ns) / 1e9, while fmpy uses k * 0.001; the two differ by one
ulp at about 14 % of the points. Such a point still commits the same
internal grid node (it snaps to it), and every output, evaluated at the
communication time itself, moves by that ulp times its rate. So libcosim
is compared bit for bit with fmpy replaying libcosim's own times, and with
fmpy's grid within that explained difference (plus 1e-12 of each peak).
"""

import numpy as np
import pytest

import interop
from interop import EXPERIMENTS


@pytest.fixture(scope="module")
def libcosim_runs(fmu_file, tmp_path_factory):
    out = tmp_path_factory.mktemp("libcosim")
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = interop.run_master("libcosim", fmu_file, EXPERIMENTS[name], out)
        return cache[name]

    return get


def test_libcosim_sees_every_variable_with_its_type(libcosim_runs, fmu_file):
    # libcosim skips what it cannot handle (FMI 2 Enumerations, for one)
    # without a word: then a start value would silently not be applied.
    from fmpy import read_model_description

    *_, seen = libcosim_runs("default")
    declared = {v.name: v.type.upper() for v in read_model_description(str(fmu_file)).modelVariables}
    assert seen == declared


@pytest.mark.parametrize("name", list(EXPERIMENTS))
def test_libcosim_equals_fmpy_on_its_times(libcosim_runs, replay, name):
    times, rows, version, _ = libcosim_runs(name)
    n = round(EXPERIMENTS[name].stop_time / interop.STEP)
    np.testing.assert_array_equal(times, [k * 1_000_000 / 1_000_000_000 for k in range(1, n + 1)])
    result = interop.assert_agrees(rows, replay(name, times), what=f"libcosim {name}")
    interop.record(version, name, "fmpy on libcosim times", result)


@pytest.mark.parametrize("name", list(EXPERIMENTS))
def test_libcosim_against_fmpy_grid(libcosim_runs, grid_reference, name):
    times, rows, version, _ = libcosim_runs(name)
    fmpy_times, reference, rates = grid_reference(name, times)
    # The clocks differ by at most one rounding.
    assert np.max(np.abs(times - fmpy_times) / fmpy_times) <= np.finfo(float).eps
    result, drift = interop.drift_explained(rows, times, reference, fmpy_times, rates, what=f"libcosim {name}")
    rms = result.worst_scaled(interop.TIME_AVERAGES)
    interop.record(version, name, "fmpy grid (k*h)", result,
                   f"1-ulp time differences ({drift:.1e} s), explained; RMS and J within {rms:.1e} of peak")
