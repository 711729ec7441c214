"""libcosim (the Open Simulation Platform's co-simulation library) through
libcosimpy: fixed-step execution, parameters as initial values, a
time-series observer, and for the input road a connection between two
instances.

libcosim's clock is integer nanoseconds: the FMU is stepped to
t_k = (k * 1e6 ns) / 1e9, while fmpy uses k * 0.001; the two differ by one
ulp at about 14 % of the points. The FMU's states and running RMS do not
see that (a communication point within rounding of an internal grid node
is that node), but the outputs evaluated at the communication time itself
-- the road x_g(t), hence tire_deflection, and the delayed x_t(t - tau) in
control_force -- move by that ulp times their slope. So libcosim is
compared bit for bit with fmpy replaying libcosim's own times, and with
fmpy's grid within that explained difference.
"""

import numpy as np
import pytest

import interop
from interop import EXPERIMENTS, OUTPUTS, TIME_EVALUATED

ON_THE_GRID = [n for n in OUTPUTS if n not in TIME_EVALUATED]


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
def test_libcosim_against_fmpy_grid(libcosim_runs, fmpy_reference, name):
    times, rows, version, _ = libcosim_runs(name)
    fmpy_times, reference = fmpy_reference(name)
    # The clocks differ by at most one rounding.
    assert np.max(np.abs(times - fmpy_times) / fmpy_times) <= np.finfo(float).eps
    result = interop.agreement(rows, reference)
    if EXPERIMENTS[name].source is None:
        # States, BA, SDD and the running RMS sit on the internal grid.
        assert result.worst(ON_THE_GRID) <= interop.RTOL, result.describe()
    # Evaluated at the communication time (and, for the input road, x_g taken
    # from a source evaluated there): within 1e-12 of each signal's peak.
    assert result.worst_scaled() <= interop.RTOL, result.describe()
    interop.record(version, name, "fmpy grid (k*h)", result, "1-ulp time differences")
