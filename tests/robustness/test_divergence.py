"""Divergence, extreme but admissible values, and calls that could hang.

Decision (documented in docs/testing.md, Robustness): a divergence makes fmi2DoStep return
fmi2Discard; the instance goes to stepFailed at the last good internal grid
node, fmi2GetRealStatus(fmi2LastSuccessfulTime) tells where, and
fmi2GetBooleanStatus(fmi2Terminated) is true. No output is ever NaN or Inf.
"""

import json
import math
import random
import re
import subprocess
import sys
from pathlib import Path

import pytest

import fmi2
from fmi2 import DISCARD, ERROR, OK, WARNING

OUTPUTS = [name for name, (_, kind, causality, _) in fmi2.variables().items()
           if causality == "output" and kind == "Real"]

UNSTABLE = {
    "negative-gain-long-delay": dict(g=-40000.0, tau=0.11, x_s_start=0.01),
    "large-gain": dict(g=150000.0, tau=0.05),
    "fast-growth": dict(g=-200000.0, tau=0.02, v_t_start=1.0),
    "gain-without-delay": dict(g=200000.0, tau=0.0, x_t_start=0.001),
    "input-road": dict(g=-40000.0, tau=0.11, road=0, x_g=0.01),
    "iso-road": dict(g=-40000.0, tau=0.11, road=2),
    "paper-road": dict(g=-40000.0, tau=0.11, road=3),
    "folded-delay": dict(g=200000.0, tau=5e-8, x_s_start=0.01),
}


def all_finite(inst):
    status, values = inst.get_real([inst.vr[n] for n in OUTPUTS])
    assert status == OK, inst.log.last()
    bad = [(n, v) for n, v in zip(OUTPUTS, values) if not math.isfinite(v)]
    assert not bad, bad
    return values


@pytest.mark.parametrize("case", sorted(UNSTABLE))
def test_divergence_is_discarded_and_outputs_stay_finite(make, case):
    inst = make()
    assert inst.initialize(**UNSTABLE[case]) == WARNING
    assert "unstable feedback" in inst.log.last()[2]
    rng = random.Random(case)
    while True:
        h = rng.choice([0.001, 0.01, 0.1, 0.5, 2.0])
        t = inst.time
        status = inst.step(h)
        if status != OK:
            break
        all_finite(inst)
        assert inst.time < 3600, "never diverged"
    assert status == DISCARD
    category, message = inst.log.last()[1:]
    assert category == "logStatusDiscard"
    m = re.match(r"fmi2DoStep: simulation diverged at t = (\S+) s: `(\w+)` = (\S+) exceeds the bound (\S+); "
                 r"the FMU stays at t = (\S+) s \(fmi2LastSuccessfulTime\)", message)
    assert m, message
    at, variable, value, bound, stays = m.groups()
    assert variable in ("x_s", "v_s", "x_h", "v_h", "x_t", "v_t")
    assert not abs(float(value)) <= float(bound)  # beyond the bound or NaN
    assert inst.machine_state() == "stepFailed"
    status, last = inst.real_status()
    assert status == OK and t <= last < t + h and last == float(stays) <= float(at)
    assert inst.boolean_status() == (OK, 1)
    all_finite(inst)
    # The last good values are there, stepping further is refused.
    assert inst.lib.fmi2DoStep(inst.c, last, 0.001, 1) == ERROR
    assert inst.lib.fmi2Terminate(inst.c) == OK
    all_finite(inst)
    assert inst.lib.fmi2Reset(inst.c) == OK
    inst.initialize()
    assert inst.step(0.1) == OK


def test_rollback_after_a_divergence(make):
    """An FMU state taken before the divergence brings the instance back."""
    inst = make()
    inst.initialize(g=-40000.0, tau=0.11, x_s_start=0.01)
    status, saved = inst.get_state()
    while inst.step(1.0) == OK:
        pass
    assert inst.machine_state() == "stepFailed"
    assert inst.lib.fmi2SetFMUstate(inst.c, saved) == OK
    assert inst.machine_state() == "stepComplete"
    assert inst.real_status() == (OK, 0.0)
    inst.time = 0.0
    assert inst.step(0.5) == OK


EXTREME = {
    "stiff-light": dict(k_t=1e9, m_t=1e-3, max_internal_step=1e-4),
    "heavy-weights": dict(w_ba=1e12, w_sdd=1e12, w_tdd=1e12),
    "big-harmonic-road": dict(road_amplitude=1e3, road_angular_frequency=1e6),
    "huge-initial-state": dict(x_s_start=1e3, v_t_start=-1e6),
    "fast-iso-road": dict(road=2, road_class=8, vehicle_speed=1e12, road_cutoff_frequency=1e12),
    "slow-paper-road": dict(road=3, road_class=8, road_sample_interval=10.0, road_cutoff_frequency=10.0),
    "explosive-paper-road": dict(road=3, road_sample_interval=0.001, road_cutoff_frequency=1e3),
    "tiny-masses": dict(m_s=1e-6, m_h=1e-6, m_t=1e-6, k_s=1e6, k_h=1e6, k_t=1e6, c_s=1.0, c_h=1.0, g=1e6),
    "input-at-the-bound": dict(road=0, x_g=1e3),
}


@pytest.mark.parametrize("case", sorted(EXTREME))
def test_extreme_admissible_values_never_give_non_finite_outputs(make, case):
    inst = make()
    status = inst.setup(0.0, None)
    inst.set(**EXTREME[case])
    assert inst.enter() == OK
    status = inst.exit()
    if status == ERROR:  # refused at initialization, naming the variable
        assert "invalid" in inst.log.last()[2]
        return
    all_finite(inst)
    for h in [1e-4, 1e-3, 0.01, 0.1, 1.0, 10.0]:
        status = inst.step(h)
        if status != OK:
            assert status == DISCARD, inst.log.last()
            assert inst.machine_state() == "stepFailed"
            break
        all_finite(inst)
    all_finite(inst)


# ------------------------------------------------------ calls that could hang

WORKER = """
import json, sys, time
sys.path.insert(0, {here!r})
import fmi2
case = json.loads(sys.argv[1])
inst = fmi2.Instance(fmi2.load())
inst.setup(case.get("start", 0.0), None)
assert inst.set(**case["values"]) == fmi2.OK, inst.log.last()
assert inst.enter() == fmi2.OK and inst.exit() in (fmi2.OK, fmi2.WARNING), inst.log.last()
began = time.monotonic()
status = inst.lib.fmi2DoStep(inst.c, case.get("start", 0.0), case["h"], 1)
print(json.dumps(dict(status=status, seconds=time.monotonic() - began, message=inst.log.last()[2])))
inst.free()
"""

HANG_CASES = {
    "huge-step-without-stop-time": (dict(values={}, h=1e9), ERROR),
    "tiny-internal-step": (dict(values=dict(variant=2, max_internal_step=1e-12), h=0.01), ERROR),
    "tiny-road-sample-interval": (dict(values=dict(road=3, road_sample_interval=1e-300), h=0.01), ERROR),
    "huge-step-iso-road": (dict(values=dict(road=2), h=1e7), ERROR),
    "late-start-tiny-step": (dict(values=dict(variant=2, max_internal_step=1e-9), start=4e3, h=1e-3), OK),
    "longest-admissible-step": (dict(values={}, h=400.0), OK),
    "longest-admissible-step-paper-road": (dict(values=dict(road=3), h=380.0), OK),
}


@pytest.mark.parametrize("case", sorted(HANG_CASES))
def test_no_call_hangs(lib, tmp_path, case):
    """Each in its own process with a timeout: a refused step names the
    work limit; an admissible one finishes within seconds."""
    spec, expected = HANG_CASES[case]
    script = tmp_path / "worker.py"
    script.write_text(WORKER.format(here=str(Path(__file__).resolve().parent)))
    done = subprocess.run([sys.executable, str(script), json.dumps(spec)], capture_output=True, text=True,
                          timeout=120, env={**__import__("os").environ, "TDVASS_SO": str(lib._name)})
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["status"] == expected, result
    assert result["seconds"] < 10.0, result
    if expected == ERROR:
        assert "internal steps" in result["message"] and "per fmi2DoStep" in result["message"], result


FORGED_GRID_INDEX = """
import json, struct, sys
sys.path.insert(0, {here!r})
import fmi2
lib = fmi2.load()
a = fmi2.Instance(lib)
a.initialize(stop=None, max_internal_step=1e-4)
assert a.step(0.0623) == fmi2.OK
status, state = a.get_state()
data = a.serialize(state)
assert data.count(struct.pack("<d", 0.0623)) >= 2  # committed and current time (node 623)
data = data.replace(struct.pack("<d", 0.0623), struct.pack("<d", 1e6))
b = fmi2.Instance(lib)
status, moved = b.deserialize(fmi2.reseal(data))
message = b.log.last()[2] if status != fmi2.OK else ""
if status == fmi2.OK:
    assert lib.fmi2SetFMUstate(b.c, moved) == fmi2.OK
    status = lib.fmi2DoStep(b.c, 1e6, 0.01, 1)
print(json.dumps(dict(status=status, message=message)))
"""


def test_forged_state_with_inconsistent_grid_index_does_not_hang(lib, tmp_path):
    """A CRC-valid state whose times are moved to 1e6 s but whose grid index
    stays at node 623 (the next step would integrate ~1e10 internal steps):
    fmi2DeSerializeFMUstate refuses it, naming the field and the value."""
    script = tmp_path / "forged.py"
    script.write_text(FORGED_GRID_INDEX.format(here=str(Path(__file__).resolve().parent)))
    try:
        done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=5,
                              env={**__import__("os").environ, "TDVASS_SO": str(lib._name)})
    except subprocess.TimeoutExpired:
        pytest.fail("fmi2DoStep on the forged state did not return within 5 s")
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["status"] == ERROR, result
    message = result["message"]
    assert "invalid serialized FMU state" in message, message
    assert "committed_time 1000000 s" in message and "grid_index = 623" in message, message
