"""Every function called in every state it is not allowed in.

The cases are generated from the state table of crates/tdvass-fmi2/src/states.rs (the
standard's table as restated there, which the unit tests check against the
table the library enforces). Each case brings a fresh instance of the real
library into the state, makes the call with otherwise valid arguments and
expects fmi2Error, the log line "fmi2X: not allowed in state Y", and the
instance still in Y. `fatal` is reachable only through an internal panic
(covered by the unit tests of crates/tdvass-fmi2/src/ffi.rs), so its column is skipped.
"""

import re
from ctypes import byref, c_char_p, c_double, c_int, c_uint
from pathlib import Path

import pytest

import fmi2
from fmi2 import ERROR, OK, array

STATES = ["instantiated", "initializationMode", "stepComplete", "stepFailed", "terminated", "error", "fatal"]
REACHABLE = STATES[:-1]


def state_table() -> dict[str, str]:
    source = (Path(__file__).resolve().parents[2] / "crates" / "tdvass-fmi2" / "src" / "states.rs").read_text()
    block = source[source.index("const EXPECTED") :]
    block = block[: block.index("];")]
    rows = dict(re.findall(r'\("(fmi2\w+)",\s*"([x.]{7})"\)', block))
    assert len(rows) == 31, rows
    return rows


TABLE = state_table()
CASES = [
    (function, state)
    for function, row in TABLE.items()
    for state, mark in zip(STATES, row)
    if mark == "." and state in REACHABLE
]


def call(inst, function):
    lib, c, vr = inst.lib, inst.c, inst.vr
    out = (c_double * 1)()
    one = array(c_int, [1])
    calls = {
        "fmi2SetDebugLogging": lambda: lib.fmi2SetDebugLogging(c, 0, 0, None),
        "fmi2FreeInstance": None,
        "fmi2SetupExperiment": lambda: lib.fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0),
        "fmi2EnterInitializationMode": lambda: lib.fmi2EnterInitializationMode(c),
        "fmi2ExitInitializationMode": lambda: lib.fmi2ExitInitializationMode(c),
        "fmi2Terminate": lambda: lib.fmi2Terminate(c),
        "fmi2Reset": lambda: lib.fmi2Reset(c),
        "fmi2GetReal": lambda: lib.fmi2GetReal(c, array(c_uint, [vr["g"]]), 1, out),
        "fmi2GetInteger": lambda: lib.fmi2GetInteger(c, array(c_uint, [vr["variant"]]), 1, one),
        "fmi2GetBoolean": lambda: lib.fmi2GetBoolean(c, array(c_uint, [vr["stable"]]), 1, one),
        "fmi2GetString": lambda: lib.fmi2GetString(c, array(c_uint, [1]), 1, (c_char_p * 1)()),
        "fmi2SetReal": lambda: lib.fmi2SetReal(c, array(c_uint, [vr["g"]]), 1, array(c_double, [5386.0])),
        "fmi2SetInteger": lambda: lib.fmi2SetInteger(c, array(c_uint, [vr["road_seed"]]), 1, one),
        "fmi2SetBoolean": lambda: lib.fmi2SetBoolean(c, array(c_uint, [vr["stable"]]), 1, one),
        "fmi2SetString": lambda: lib.fmi2SetString(c, array(c_uint, [1]), 1, (c_char_p * 1)(b"x")),
        "fmi2GetDirectionalDerivative": lambda: lib.fmi2GetDirectionalDerivative(
            c, array(c_uint, [vr["x_s"]]), 1, array(c_uint, [vr["x_s"]]), 1, array(c_double, [1.0]), out
        ),
        "fmi2SetRealInputDerivatives": lambda: lib.fmi2SetRealInputDerivatives(
            c, array(c_uint, [vr["x_g"]]), 1, one, array(c_double, [0.0])
        ),
        "fmi2GetRealOutputDerivatives": lambda: lib.fmi2GetRealOutputDerivatives(
            c, array(c_uint, [vr["x_s"]]), 1, one, out
        ),
        "fmi2DoStep": lambda: lib.fmi2DoStep(c, inst.time, 0.001, 1),
        "fmi2CancelStep": lambda: lib.fmi2CancelStep(c),
        "fmi2GetStatus": lambda: lib.fmi2GetStatus(c, fmi2.DO_STEP_STATUS, one),
        "fmi2GetRealStatus": lambda: lib.fmi2GetRealStatus(c, fmi2.LAST_SUCCESSFUL_TIME, out),
        "fmi2GetIntegerStatus": lambda: lib.fmi2GetIntegerStatus(c, fmi2.DO_STEP_STATUS, one),
        "fmi2GetBooleanStatus": lambda: lib.fmi2GetBooleanStatus(c, fmi2.TERMINATED, one),
        "fmi2GetStringStatus": lambda: lib.fmi2GetStringStatus(c, fmi2.DO_STEP_STATUS, (c_char_p * 1)()),
    }
    return calls[function]()


@pytest.fixture(scope="module")
def forged_states(lib):
    """Serialized states in stepFailed (a real divergence) and in error
    (a stepComplete state whose machine-state byte is set to `error`)."""
    inst = fmi2.Instance(lib)
    inst.initialize(g=-40000.0, tau=0.11, x_s_start=0.01)
    t = 0.0
    while (s := inst.lib.fmi2DoStep(inst.c, t, 5.0, 1)) == OK:
        t += 5.0
    assert s == fmi2.DISCARD
    _, failed = inst.get_state()
    step_failed = inst.serialize(failed)
    inst.free()
    inst = fmi2.Instance(lib)
    inst.initialize()
    _, state = inst.get_state()
    data = bytearray(inst.serialize(state))
    inst.free()
    at, _ = fmi2.serialized_fields(bytes(data))
    assert data[at] == STATES.index("stepComplete")
    data[at] = STATES.index("error")
    return {"stepFailed": step_failed, "error": fmi2.reseal(data)}


def bring_to(make, forged_states, state):
    inst = make()
    if state == "instantiated":
        pass
    elif state == "initializationMode":
        assert inst.setup(0.0, 15.0) == OK and inst.enter() == OK
    elif state in ("stepComplete", "terminated"):
        inst.initialize(stop=15.0)
        if state == "terminated":
            assert inst.lib.fmi2Terminate(inst.c) == OK
    else:
        status, handle = inst.deserialize(forged_states[state])
        assert status == OK, inst.log.last()
        assert inst.lib.fmi2SetFMUstate(inst.c, handle) == OK
    assert inst.machine_state() == state
    return inst


def test_the_generated_cases_cover_the_table():
    # 67 refusals in the six reachable states.
    assert len(CASES) == 67


@pytest.mark.parametrize("function, state", CASES, ids=[f"{f}-in-{s}" for f, s in CASES])
def test_call_in_a_state_where_it_is_not_allowed(make, forged_states, function, state):
    inst = bring_to(make, forged_states, state)
    before = len(inst.log.messages)
    assert call(inst, function) == ERROR
    assert inst.log.since(before) == [(ERROR, "logStatusError", f"{function}: not allowed in state {state}")]
    assert inst.machine_state() == state


@pytest.mark.parametrize("state", REACHABLE)
def test_free_instance_and_fmu_states_are_allowed_everywhere_but_fatal(make, forged_states, state):
    inst = bring_to(make, forged_states, state)
    status, handle = inst.get_state()
    assert status == OK
    assert inst.lib.fmi2SetFMUstate(inst.c, handle) == OK
    assert inst.machine_state() == state
    assert inst.lib.fmi2FreeFMUstate(inst.c, byref(handle)) == OK
    assert inst.lib.fmi2Reset(inst.c) == OK
    assert inst.machine_state() == "instantiated"
    inst.free()
    assert not inst.c
