"""Outputs must not depend on how a master counts time or holds inputs.

Most masters accumulate the communication time (`t += h`); some compute it
(`t = k h`) or count integer nanoseconds. The FMU commits the same internal
grid nodes either way (a requested time within the snap tolerance of a node
is that node), so the RMS integrals are the same; every output is evaluated
at the requested time itself, so an output may differ only by the clock
drift times its rate of change.
"""

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmu_helpers import OUTPUTS, RMS, accumulated_times, grid

EXPERIMENTS = {
    "default": {},
    "CS ISO 8608 C seed 7": {"variant": 1, "road": 2, "road_class": 3, "road_seed": 7},
    "TDVASS tau 0.03 g 20000": {"tau": 0.03, "g": 20000.0},
}
STEPS = {"1 ms": 1e-3, "1/3 ms": 1e-3 / 3.0, "7.3 ms": 7.3e-3}


def run(make_slave, label, values, step, stop, accumulate):
    """Outputs, their first derivatives and the times, at every
    communication point of a run with times `k h` or accumulated."""
    slave = make_slave(label).start(stop_time=stop + 1.0, **values)
    n = int(stop / step + 1e-9)
    times = accumulated_times(0.0, n, step) if accumulate else [k * step for k in range(1, n + 1)]
    vrs = [slave.vr[name] for name in OUTPUTS]
    outputs, rates = [], []
    for t in times:
        slave.fmu.doStep(currentCommunicationPoint=slave.time, communicationStepSize=step)
        slave.time = t
        outputs.append(slave.fmu.getReal(vrs))
        rates.append(slave.fmu.getRealOutputDerivatives(vrs, [1] * len(vrs)))
    return np.array(times), np.array(outputs), np.array(rates)


@pytest.mark.parametrize("step_label", STEPS)
@pytest.mark.parametrize("experiment", EXPERIMENTS)
def test_accumulated_and_exact_times_agree(make_slave, experiment, step_label):
    step, stop = STEPS[step_label], 15.0
    values = EXPERIMENTS[experiment]
    t_exact, exact, rates = run(make_slave, "exact", values, step, stop, accumulate=False)
    t_drift, drifting, _ = run(make_slave, "accumulated", values, step, stop, accumulate=True)
    drift = np.abs(t_drift - t_exact)
    assert drift.max() > 0.0 or step_label == "7.3 ms", "the accumulated clock drifts"
    scale = np.abs(exact).max(axis=0)
    difference = np.abs(drifting - exact)
    # Each output: 1e-12 of its largest magnitude, plus the drift times its
    # rate (twice, for the rate's change over the drift).
    allowed = 1e-12 * scale + 2.0 * drift[:, None] * np.abs(rates)
    worst = np.argmax((difference - allowed).max(axis=0))
    assert (difference <= allowed).all(), (
        f"{OUTPUTS[worst]}: {difference[:, worst].max():.3e} > allowed {allowed[:, worst].max():.3e}"
    )
    excess = (difference / scale).max(axis=0)
    print(f"{experiment}, {step_label}: largest drift {drift.max():.2e} s;", ", ".join(
        f"{name} {value:.1e}" for name, value in zip(OUTPUTS, excess)))


def test_state_saved_after_accumulated_steps_continues_in_a_fresh_process(make_slave, unzipdir, tmp_path):
    step = 1e-3
    slave = make_slave().start(stop_time=5.0)
    times = accumulated_times(0.0, 2000, step)
    for t in times:
        slave.fmu.doStep(currentCommunicationPoint=slave.time, communicationStepSize=step)
        slave.time = t
    t_saved = slave.time
    assert t_saved != 2.0, "the accumulated time is off the exact one"
    state = slave.fmu.getFMUstate()
    data = slave.fmu.serializeFMUstate(state)
    slave.fmu.freeFMUstate(state)
    here = [[v.hex() for v in row] for row in slave.run(accumulated_times(t_saved, 500, step))]
    state_file = tmp_path / "state.bin"
    state_file.write_bytes(data)
    worker = Path(__file__).resolve().parent / "fmu_helpers.py"
    done = subprocess.run(
        [sys.executable, str(worker), "continue-accumulated", str(unzipdir), str(state_file), repr(t_saved), "500", "1e-3"],
        capture_output=True,
        text=True,
        check=True,
    )
    assert json.loads(done.stdout) == here, "bit-identical continuation"


def feed_harmonic_road(make_slave, label, step, stop, first_slope=False, **values):
    """RMS values with x_g = 0.05 sin 5t set at each communication point
    (held or extrapolated by the FMU), and the log. `first_slope`: the
    master also gives the first step's slope (fmi2SetRealInputDerivatives),
    which no extrapolation can know."""
    fed = make_slave(label).start(stop_time=stop, road=0, **values)
    for k, t in enumerate(grid(0.0, stop, step)):
        fed.set(x_g=0.05 * math.sin(5.0 * fed.time))
        if first_slope and k == 0:
            fed.fmu.setRealInputDerivatives([fed.vr["x_g"]], [1], [0.25])
        fed.step_to(t)
    return fed.get(RMS), fed.log


def built_in_road(make_slave, stop):
    harmonic = make_slave("harmonic").start(stop_time=stop)
    harmonic.step_to(stop)
    return harmonic.get(RMS)


def test_extrapolated_input_reproduces_the_built_in_road(make_slave):
    # Linear extrapolation through the last two values (1) lags the road by
    # about (5/12) h² x_g'' on average over a step, the line fitted to the
    # parabola through the last three values (2) by h² x_g'' / 48, the hold
    # (0) by h x_g' / 2. The first step holds whatever the setting (one
    # value says nothing of the slope): on this road, which starts with
    # slope 0.25 m/s, that alone excites a wheel-hop transient worth 4e-4 of
    # RMS(TDD) at 1 ms; a master that gives the first step's slope avoids it.
    stop = 15.0
    reference = built_in_road(make_slave, stop)
    errors = {}
    for step in (1e-3, 1e-2):
        for extrapolation in (0, 1, 2):
            for first_slope in (False, True):
                ours, _ = feed_harmonic_road(make_slave, f"{step} {extrapolation} {first_slope}", step, stop,
                                             first_slope=first_slope, input_extrapolation=extrapolation)
                key = step, extrapolation, first_slope
                errors[key] = [abs(a / b - 1.0) for a, b in zip(ours, reference)]
                print(f"step {step} s, input_extrapolation = {extrapolation}, first slope given {first_slope}: "
                      "relative RMS errors (BA, SDD, TDD)", ", ".join(f"{e:.2e}" for e in errors[key]))
    assert max(errors[1e-3, 1, True]) < 1e-4, errors[1e-3, 1, True]
    assert max(errors[1e-3, 2, True]) < 1e-5, errors[1e-3, 2, True]
    assert max(errors[1e-3, 2, False][:2]) < 1e-4 and errors[1e-3, 2, False][2] < 1e-3, errors[1e-3, 2, False]
    for step in (1e-3, 1e-2):
        held, linear, fitted = (errors[step, mode, True] for mode in (0, 1, 2))
        assert held[2] > 5.0 * linear[2] > 5.0 * fitted[2], (held, linear, fitted)


def test_long_held_steps_warn_once_and_short_ones_stay_silent(make_slave):
    _, quiet = feed_harmonic_road(make_slave, "1 ms", 1e-3, 1.0)
    assert not [m for s, _, m in quiet.messages if s == 1], quiet.text()
    _, log = feed_harmonic_road(make_slave, "10 ms", 1e-2, 1.0)
    warnings = [m for s, _, m in log.messages if s == 1]
    assert len(warnings) == 1, warnings
    assert "0.01 s" in warnings[0] and "input_extrapolation = 2" in warnings[0], warnings[0]
    _, extrapolated = feed_harmonic_road(make_slave, "10 ms extrapolated", 1e-2, 1.0, input_extrapolation=2)
    assert not [m for s, _, m in extrapolated.messages if s == 1], extrapolated.text()
