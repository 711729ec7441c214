"""ecos (ecospy): a simulation structure with parameter sets, fixed-step
stepping read through its get_real, and for the input road a connection
between two instances.

ecos's clock is a running sum, t_{k+1} = t_k + h, so with h = 1 ms its
communication times drift from k * h by up to 3e-12 s (15 s ends at
14.999999999997126 s). The FMU computes exactly what it is asked at those
times, so ecos is compared bit for bit with fmpy replaying ecos's own
times. Against fmpy's grid, a drifted time still commits the same internal
grid nodes (it snaps to them), so the only difference is the drift itself:
every output may differ by the drift times its rate of change, plus 1e-12
of its peak. With a dyadic step (2^-10 s) ecos's sum is exact and it agrees
with fmpy's grid bit for bit.
"""

from dataclasses import replace

import numpy as np
import pytest

import interop
from interop import EXPERIMENTS, OUTPUTS



@pytest.fixture(scope="module")
def ecos_runs(fmu_file, tmp_path_factory):
    out = tmp_path_factory.mktemp("ecos")
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = interop.run_master("ecos", fmu_file, EXPERIMENTS[name], out)
        return cache[name]

    return get


@pytest.mark.parametrize("name", list(EXPERIMENTS))
def test_ecos_equals_fmpy_on_its_times(ecos_runs, replay, name):
    times, rows, version, _ = ecos_runs(name)
    expected = np.cumsum(np.full(len(times), interop.STEP))  # the running sum
    np.testing.assert_array_equal(times, expected)
    result = interop.assert_agrees(rows, replay(name, times), what=f"ecos {name}")
    interop.record(version, name, "fmpy on ecos times", result)


@pytest.mark.parametrize("name", list(EXPERIMENTS))
def test_ecos_against_fmpy_grid(ecos_runs, grid_reference, name):
    times, rows, version, _ = ecos_runs(name)
    fmpy_times, reference, rates = grid_reference(name, times)
    result, drift = interop.drift_explained(rows, times, reference, fmpy_times, rates, what=f"ecos {name}")
    assert 0.0 < drift < 1e-11, drift
    rms = result.worst_scaled(interop.TIME_AVERAGES)
    interop.record(version, name, "fmpy grid (k*h)", result,
                   f"clock drift up to {drift:.1e} s, explained; RMS and J within {rms:.1e} of peak")


def test_ecos_with_a_dyadic_step_equals_fmpy_grid(fmu_file, tmp_path):
    # 2^-10 s: every partial sum is exact, so ecos's and fmpy's clocks agree.
    import fmpy

    step = 2.0**-10
    experiment = replace(EXPERIMENTS["cs_iso8608"], name="cs_dyadic", stop_time=4.0, step_size=step)
    times, rows, version, _ = interop.run_master("ecos", fmu_file, experiment, tmp_path)
    result = fmpy.simulate_fmu(str(fmu_file), start_values=experiment.start_values,
                               stop_time=experiment.stop_time, output_interval=step, output=OUTPUTS)
    np.testing.assert_array_equal(times, result["time"][1:])
    reference = np.column_stack([result[n][1:] for n in OUTPUTS])
    agreed = interop.assert_agrees(rows, reference, what="ecos dyadic")
    interop.record(version, "cs_iso8608", "fmpy grid, h = 2^-10 s", agreed, "4 s")
