"""Divergence in the FMI 3.0 FMU, reported as in FMI 2.0: fmi3DoStep
returns fmi3Discard with lastSuccessfulTime at the last good internal grid
node and terminateSimulation = true; the instance is in Step Mode after a
discarded step; no output is ever NaN or Inf; also with intermediate
updates inside the diverging step."""

import math
import random
import re

import pytest

import fmi3
from fmi3 import DISCARD, ERROR, OK, WARNING

OUTPUTS = [name for name, (_, kind, causality, _) in fmi3.variables().items()
           if causality == "output" and kind == "Float64"]

UNSTABLE = {
    "negative-gain-long-delay": dict(g=-40000.0, tau=0.11, x_s_start=0.01),
    "large-gain": dict(g=150000.0, tau=0.05),
    "gain-without-delay": dict(g=200000.0, tau=0.0, x_t_start=0.001),
    "input-road": dict(g=-40000.0, tau=0.11, road=0, x_g=0.01),
    "iso-road": dict(g=-40000.0, tau=0.11, road=2),
}


def all_finite(inst):
    status, values = inst.get_float64([inst.vr[n] for n in OUTPUTS])
    assert status == OK, inst.log.last()
    bad = [(n, v) for n, v in zip(OUTPUTS, values) if not math.isfinite(v)]
    assert not bad, bad


@pytest.mark.parametrize("case", sorted(UNSTABLE))
def test_divergence_is_discarded_and_outputs_stay_finite(make3, case):
    inst = make3()
    assert inst.initialize(**UNSTABLE[case]) == WARNING
    assert "unstable feedback" in inst.log.last()[2]
    rng = random.Random(case)
    while True:
        h = rng.choice([0.001, 0.01, 0.1, 0.5, 2.0])
        t = inst.time
        status, event, terminate, early, last = inst.do_step(t, h)
        if status != OK:
            break
        assert (event, terminate, early, last) == (False, False, False, t + h)
        inst.time = t + h
        all_finite(inst)
        assert inst.time < 3600, "never diverged"
    assert status == DISCARD
    assert (event, terminate, early) == (False, True, False)
    category, message = inst.log.last()[1:]
    assert category == "logStatusDiscard"
    m = re.match(r"fmi3DoStep: simulation diverged at t = (\S+) s: `(\w+)` = (\S+) exceeds the bound (\S+); "
                 r"the FMU stays at t = (\S+) s \(lastSuccessfulTime\) and asks to terminate \(terminateSimulation\)",
                 message)
    assert m, message
    at, variable, value, bound, stays = m.groups()
    assert variable in ("x_s", "v_s", "x_h", "v_h", "x_t", "v_t")
    assert not abs(float(value)) <= float(bound)
    assert t <= last < t + h and last == float(stays) <= float(at)
    assert inst.machine_state() == "Step Mode after a discarded step"
    all_finite(inst)
    assert inst.get_values("fmi3GetFloat64", [inst.vr["time"]]) == (OK, [last])
    # The last good values are there, stepping further is refused.
    assert inst.do_step(last, 0.001)[0] == ERROR
    assert inst.lib.fmi3Terminate(inst.c) == OK
    all_finite(inst)
    assert inst.lib.fmi3Reset(inst.c) == OK
    inst.initialize(stop=15.0)
    assert inst.step(0.1) == OK


def test_rollback_after_a_divergence(make3):
    inst = make3()
    inst.initialize(g=-40000.0, tau=0.11, x_s_start=0.01)
    status, saved = inst.get_state()
    while inst.step(1.0) == OK:
        pass
    assert inst.machine_state() == "Step Mode after a discarded step"
    assert inst.lib.fmi3SetFMUState(inst.c, saved) == OK
    assert inst.machine_state() == "Step Mode"
    inst.time = 0.0
    assert inst.do_step(0.0, 0.5) == (OK, False, False, False, 0.5)


def test_divergence_inside_a_step_with_intermediate_updates(make3):
    """Outputs read in the updates before the divergence are finite, the
    discard is at or after the last update, and no update comes after it."""
    seen = []

    def on_update(inst, time, can_return_early):
        status, values = inst.get_float64([inst.vr[n] for n in OUTPUTS])
        seen.append((time, status, all(math.isfinite(v) for v in values)))
        return False

    inst = make3(intermediate=on_update, early_return=True)
    inst.set(intermediate_update_interval=0.01)
    inst.initialize(g=-40000.0, tau=0.11, x_s_start=0.01)
    status, event, terminate, early, last = inst.do_step(0.0, 60.0)
    assert status == DISCARD and terminate and not early
    assert seen and all(s == OK and finite for _, s, finite in seen)
    assert seen[-1][0] <= last
    assert [t for t, _, _ in seen] == sorted(t for t, _, _ in seen)
    all_finite(inst)


def test_early_return_before_the_divergence(make3):
    """An early return asked for before the divergence is taken, at the
    update's time, and the run can go on to the discard."""
    inst = make3(intermediate=lambda inst, time, can: time >= 1.0, early_return=True)
    inst.set(intermediate_update_interval=0.1)
    inst.initialize(g=-40000.0, tau=0.11, x_s_start=0.01)
    status, _, terminate, early, last = inst.do_step(0.0, 60.0)
    assert (status, terminate, early) == (OK, False, True)
    assert 1.0 <= last < 1.2 and last == inst.updates[-1]
    all_finite(inst)
    inst.intermediate = None
    status, _, terminate, early, _ = inst.do_step(last, 60.0 - last)
    assert (status, terminate, early) == (DISCARD, True, False)
