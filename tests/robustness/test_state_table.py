"""Every function called in every state: refused where the state table
forbids it, never a panic where it allows it.

The cases are generated from the state table of crates/tdvass-fmi2/src/states.rs (the
standard's table as restated there, which the unit tests check against the
table the library enforces), for both kinds of instance: a Co-Simulation
instance reaches instantiated, initializationMode, stepComplete,
stepFailed, terminated and error; a Model Exchange instance reaches
instantiated, initializationMode, eventMode, continuousTimeMode,
terminated and error. Each case brings a fresh instance of the real
library into the state, makes the call with otherwise valid arguments and
expects fmi2Error, the log line "fmi2X: not allowed in state Y" and nothing
else, the instance still in Y and its serialized state unchanged. `fatal`
is reachable only through an internal panic (covered by the unit tests of
crates/tdvass-fmi2/src/ffi.rs), so its column is skipped.

Where the table allows a call, the call with valid arguments succeeds on
the kind of instance it belongs to; a Model Exchange function on a
Co-Simulation instance (or the reverse) in a state both share may be
refused by the instance, with fmi2Error and a reason, never with a panic.
"""

import re
from ctypes import byref, c_char_p, c_double, c_int, c_uint, c_void_p
from pathlib import Path

import pytest

import fmi2
from fmi2 import ERROR, OK, WARNING, array

STATES = ["instantiated", "initializationMode", "stepComplete", "stepFailed", "terminated", "error", "fatal",
          "eventMode", "continuousTimeMode"]
REACHABLE = {
    "cs": ["instantiated", "initializationMode", "stepComplete", "stepFailed", "terminated", "error"],
    "me": ["instantiated", "initializationMode", "eventMode", "continuousTimeMode", "terminated", "error"],
}
MODEL_EXCHANGE_FUNCTIONS = {
    "fmi2EnterEventMode", "fmi2NewDiscreteStates", "fmi2EnterContinuousTimeMode", "fmi2CompletedIntegratorStep",
    "fmi2SetTime", "fmi2SetContinuousStates", "fmi2GetDerivatives", "fmi2GetEventIndicators",
    "fmi2GetContinuousStates", "fmi2GetNominalsOfContinuousStates",
}
CO_SIMULATION_FUNCTIONS = {
    "fmi2SetRealInputDerivatives", "fmi2GetRealOutputDerivatives", "fmi2DoStep", "fmi2CancelStep",
    "fmi2GetStatus", "fmi2GetRealStatus", "fmi2GetIntegerStatus", "fmi2GetBooleanStatus", "fmi2GetStringStatus",
}


def state_table() -> dict[str, str]:
    source = (Path(__file__).resolve().parents[2] / "crates" / "tdvass-fmi2" / "src" / "states.rs").read_text()
    block = source[source.index("const EXPECTED") :]
    block = block[: block.index("];")]
    rows = dict(re.findall(r'\("(fmi2\w+)",\s*"([x.]{9})"\)', block))
    assert len(rows) == 41, rows
    return rows


TABLE = state_table()
CASES = [
    (kind, function, state)
    for kind, reachable in REACHABLE.items()
    for function, row in TABLE.items()
    for state, mark in zip(STATES, row)
    if mark == "." and state in reachable
]
ALLOWED = [
    (kind, function, state)
    for kind, reachable in REACHABLE.items()
    for function, row in TABLE.items()
    for state, mark in zip(STATES, row)
    if mark == "x" and state in reachable and function != "fmi2FreeInstance"
]


def belongs_to(function, kind):
    """Whether `function` is one of the instance kind's own (or common)."""
    other = MODEL_EXCHANGE_FUNCTIONS if kind == "cs" else CO_SIMULATION_FUNCTIONS
    return function not in other


def call(inst, function):
    lib, c, vr = inst.lib, inst.c, inst.vr
    out = (c_double * 1)()
    one = array(c_int, [1])
    nx = (c_double * fmi2.NX)()  # zeros: valid continuous states
    flag = c_int()
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
        "fmi2GetString": lambda: lib.fmi2GetString(c, None, 0, None),
        # g is tunable: settable in every state that allows setting, but in
        # Continuous-Time Mode (Model Exchange); there x_g, an input (road = 0).
        "fmi2SetReal": lambda: lib.fmi2SetReal(c, *((array(c_uint, [vr["x_g"]]), 1, array(c_double, [0.0]))
                                                    if inst.road_input else
                                                    (array(c_uint, [vr["g"]]), 1, array(c_double, [5386.0])))),
        "fmi2SetInteger": lambda: lib.fmi2SetInteger(c, None, 0, None),
        "fmi2SetBoolean": lambda: lib.fmi2SetBoolean(c, None, 0, None),
        "fmi2SetString": lambda: lib.fmi2SetString(c, None, 0, None),
        "fmi2GetFMUstate": lambda: lib.fmi2GetFMUstate(c, byref(c_void_p())),
        "fmi2SetFMUstate": lambda: lib.fmi2SetFMUstate(c, inst.saved),
        "fmi2FreeFMUstate": lambda: lib.fmi2FreeFMUstate(c, byref(c_void_p(inst.saved.value))),
        "fmi2SerializedFMUstateSize": lambda: lib.fmi2SerializedFMUstateSize(c, inst.saved, byref(fmi2.c_size_t())),
        "fmi2SerializeFMUstate": lambda: lib.fmi2SerializeFMUstate(
            c, inst.saved, (fmi2.c_char * len(inst.saved_bytes))(), len(inst.saved_bytes)
        ),
        "fmi2DeSerializeFMUstate": lambda: lib.fmi2DeSerializeFMUstate(
            c, (fmi2.c_char * len(inst.saved_bytes)).from_buffer_copy(inst.saved_bytes), len(inst.saved_bytes),
            byref(c_void_p()),
        ),
        "fmi2GetDirectionalDerivative": lambda: lib.fmi2GetDirectionalDerivative(
            c, array(c_uint, [vr["x_s"]]), 1, array(c_uint, [vr["x_s"]]), 1, array(c_double, [1.0]), out
        ),
        "fmi2SetRealInputDerivatives": lambda: lib.fmi2SetRealInputDerivatives(c, None, 0, None, None),
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
        "fmi2EnterEventMode": lambda: lib.fmi2EnterEventMode(c),
        "fmi2NewDiscreteStates": lambda: lib.fmi2NewDiscreteStates(c, byref(fmi2.EventInfo())),
        "fmi2EnterContinuousTimeMode": lambda: lib.fmi2EnterContinuousTimeMode(c),
        "fmi2CompletedIntegratorStep": lambda: lib.fmi2CompletedIntegratorStep(c, 1, byref(flag), byref(flag)),
        "fmi2SetTime": lambda: lib.fmi2SetTime(c, inst.time),
        "fmi2SetContinuousStates": lambda: lib.fmi2SetContinuousStates(c, nx, fmi2.NX),
        "fmi2GetDerivatives": lambda: lib.fmi2GetDerivatives(c, nx, fmi2.NX),
        "fmi2GetEventIndicators": lambda: lib.fmi2GetEventIndicators(c, out, fmi2.NZ),
        "fmi2GetContinuousStates": lambda: lib.fmi2GetContinuousStates(c, nx, fmi2.NX),
        "fmi2GetNominalsOfContinuousStates": lambda: lib.fmi2GetNominalsOfContinuousStates(c, nx, fmi2.NX),
    }
    assert set(calls) == set(TABLE)
    return calls[function]()


def forge(data: bytes, state: str) -> bytes:
    """`data` (a serialized state) with its machine-state byte set to `state`."""
    data = bytearray(data)
    at, _ = fmi2.serialized_fields(bytes(data))
    data[at] = STATES.index(state)
    return fmi2.reseal(data)


@pytest.fixture(scope="module")
def forged_states(lib):
    """Serialized states in stepFailed (a real divergence) and in error (a
    stepComplete or eventMode state whose machine-state byte is set to
    `error`), by instance kind."""
    inst = fmi2.Instance(lib)
    inst.initialize(g=-40000.0, tau=0.11, x_s_start=0.01)
    t = 0.0
    while (s := inst.lib.fmi2DoStep(inst.c, t, 5.0, 1)) == OK:
        t += 5.0
    assert s == fmi2.DISCARD
    step_failed = inst.snapshot()
    inst.free()
    inst = fmi2.Instance(lib)
    inst.initialize()
    data = inst.snapshot()
    inst.free()
    assert data[fmi2.serialized_fields(data)[0]] == STATES.index("stepComplete")
    me = fmi2.Instance(lib, fmu_type=fmi2.MODEL_EXCHANGE)
    me.initialize_model_exchange()
    me_data = me.snapshot()
    me.free()
    assert me_data[fmi2.serialized_fields(me_data)[0]] == STATES.index("eventMode")
    return {("cs", "stepFailed"): step_failed, ("cs", "error"): forge(data, "error"),
            ("me", "error"): forge(me_data, "error")}


def keep_a_state(inst):
    status, inst.saved = inst.get_state()
    assert status == OK, inst.log.last()
    inst.saved_bytes = inst.serialize(inst.saved)


def bring_to(make, forged_states, kind, state):
    inst = make(fmu_type=fmi2.MODEL_EXCHANGE if kind == "me" else fmi2.CO_SIMULATION)
    inst.road_input = False
    if state == "instantiated":
        pass
    elif state == "initializationMode":
        assert inst.setup(0.0, 15.0) == OK and inst.enter() == OK
    elif state in ("stepComplete", "eventMode", "continuousTimeMode", "terminated"):
        # Continuous-Time Mode: with the road as input (the setter there).
        inst.road_input = state == "continuousTimeMode"
        inst.initialize(stop=15.0, **({"road": 0} if inst.road_input else {}))
        if state == "continuousTimeMode":
            assert inst.enter_continuous_time_mode() == OK
        if state == "terminated":
            assert inst.lib.fmi2Terminate(inst.c) == OK
    else:
        status, handle = inst.deserialize(forged_states[kind, state])
        assert status == OK, inst.log.last()
        assert inst.lib.fmi2SetFMUstate(inst.c, handle) == OK
    assert inst.machine_state() == state
    keep_a_state(inst)
    return inst


def test_the_generated_cases_cover_the_table():
    # Co-Simulation: 67 refusals of the Co-Simulation functions in its six
    # states (as before Model Exchange), and of the 10 Model Exchange
    # functions: all 10 in instantiated, initializationMode, stepComplete and
    # stepFailed, 6 in terminated and error (the 4 getters are allowed
    # there). Model Exchange: the same 25 + 21 + 17 + 22 in the shared
    # states, 14 in eventMode and 13 in continuousTimeMode.
    refused = {kind: sum(1 for k, _, _ in CASES if k == kind) for kind in REACHABLE}
    assert refused == {"cs": 67 + 52, "me": 25 + 21 + 17 + 22 + 14 + 13}, refused
    assert len(CASES) + len(ALLOWED) + 2 * 6 == 41 * 6 * 2  # fmi2FreeInstance: 6 states by kind


@pytest.mark.parametrize("kind, function, state", CASES, ids=[f"{k}-{f}-in-{s}" for k, f, s in CASES])
def test_call_in_a_state_where_it_is_not_allowed(make, forged_states, kind, function, state):
    inst = bring_to(make, forged_states, kind, state)
    before = inst.snapshot()
    count = len(inst.log.messages)
    assert call(inst, function) == ERROR
    assert inst.log.since(count) == [(ERROR, "logStatusError", f"{function}: not allowed in state {state}")]
    assert inst.machine_state() == state
    assert inst.snapshot() == before


@pytest.mark.parametrize("kind, function, state", ALLOWED, ids=[f"{k}-{f}-in-{s}" for k, f, s in ALLOWED])
def test_call_in_a_state_where_it_is_allowed(make, forged_states, kind, function, state):
    """An allowed call passes the state table. On its own kind of instance
    it succeeds; a function of the other kind may be refused by the
    instance (fmi2Error, a reason naming the function), never fmi2Fatal."""
    inst = bring_to(make, forged_states, kind, state)
    count = len(inst.log.messages)
    status = call(inst, function)
    log = inst.log.since(count)
    assert status != fmi2.FATAL, log
    assert not [m for m in log if "not allowed in state" in m[2] or m[0] == fmi2.FATAL], log
    # fmi2DoStepStatus asked of fmi2GetStatus, fmi2GetIntegerStatus or
    # fmi2GetStringStatus: fmi2Discard (this FMU steps synchronously).
    expected = {"fmi2GetStatus": fmi2.DISCARD, "fmi2GetIntegerStatus": fmi2.DISCARD,
                "fmi2GetStringStatus": fmi2.DISCARD}.get(function, OK)
    if function == "fmi2ExitInitializationMode" and status == WARNING:
        expected = WARNING
    if belongs_to(function, kind):
        assert status == expected, log
    else:
        assert status in (expected, ERROR), log
        if status == ERROR:
            assert [m[0] for m in log] == [ERROR] and log[0][2].startswith(f"{function}: "), log
            assert inst.machine_state() == state


@pytest.mark.parametrize("kind, state", [(k, s) for k, states in REACHABLE.items() for s in states])
def test_free_instance_and_fmu_states_are_allowed_everywhere_but_fatal(make, forged_states, kind, state):
    inst = bring_to(make, forged_states, kind, state)
    status, handle = inst.get_state()
    assert status == OK
    assert inst.lib.fmi2SetFMUstate(inst.c, handle) == OK
    assert inst.machine_state() == state
    assert inst.lib.fmi2FreeFMUstate(inst.c, byref(handle)) == OK
    assert inst.lib.fmi2Reset(inst.c) == OK
    assert inst.machine_state() == "instantiated"
    inst.free()
    assert not inst.c


# ----------------------------------------------- FMU states across the kinds


@pytest.fixture(scope="module")
def kinds_states(lib):
    """Serialized states of each kind: Co-Simulation in stepComplete, Model
    Exchange in eventMode and continuousTimeMode (codes 7 and 8)."""
    cs = fmi2.Instance(lib)
    cs.initialize()
    assert cs.step(0.01) == OK
    me = fmi2.Instance(lib, fmu_type=fmi2.MODEL_EXCHANGE)
    me.initialize_model_exchange()
    event = me.snapshot()
    assert me.enter_continuous_time_mode() == OK
    assert me.euler_step(1e-4)[0] == OK
    continuous = me.snapshot()
    states = {"stepComplete": cs.snapshot(), "eventMode": event, "continuousTimeMode": continuous}
    cs.free()
    me.free()
    for state, data in states.items():
        assert data[fmi2.serialized_fields(data)[0]] == STATES.index(state)
    assert STATES.index("eventMode") == 7 and STATES.index("continuousTimeMode") == 8
    return states


@pytest.mark.parametrize("state", ["eventMode", "continuousTimeMode"])
def test_a_model_exchange_state_restores_only_into_a_model_exchange_instance(make, kinds_states, state):
    data = kinds_states[state]
    me = make(fmu_type=fmi2.MODEL_EXCHANGE)
    status, handle = me.deserialize(data)
    assert status == OK, me.log.last()
    assert me.lib.fmi2SetFMUstate(me.c, handle) == OK
    assert me.machine_state() == state
    assert me.snapshot() == data
    cs = make()
    for setup in (lambda: None, lambda: cs.initialize()):
        setup()
        before = cs.machine_state()
        status, handle = cs.deserialize(data)
        assert status == ERROR and not handle.value
        assert cs.log.last() == (ERROR, "logStatusError", "fmi2DeSerializeFMUstate: a Model Exchange state cannot "
                                                          "be restored into a Co-Simulation instance")
        assert cs.machine_state() == before


def test_a_co_simulation_state_restores_only_into_a_co_simulation_instance(make, kinds_states):
    data = kinds_states["stepComplete"]
    me = make(fmu_type=fmi2.MODEL_EXCHANGE)
    status, handle = me.deserialize(data)
    assert status == ERROR and not handle.value
    assert me.log.last() == (ERROR, "logStatusError", "fmi2DeSerializeFMUstate: a Co-Simulation state cannot be "
                                                      "restored into a Model Exchange instance")
    assert me.machine_state() == "instantiated"


@pytest.mark.parametrize("state", ["eventMode", "continuousTimeMode"])
def test_a_co_simulation_state_forged_into_a_model_exchange_phase_is_refused(make, kinds_states, state):
    """A simulator in eventMode or continuousTimeMode (phase codes 7, 8) is
    not a state any instance can be in."""
    forged = forge(kinds_states["stepComplete"], state)
    for kind in (fmi2.CO_SIMULATION, fmi2.MODEL_EXCHANGE):
        inst = make(fmu_type=kind)
        status, handle = inst.deserialize(forged)
        assert status == ERROR and not handle.value
        message = inst.log.last()[2]
        assert message.startswith("fmi2DeSerializeFMUstate: invalid serialized FMU state: "), message
        assert f"state {state}" in message, message


@pytest.mark.parametrize("state", ["stepComplete", "stepFailed"])
@pytest.mark.parametrize("source", ["eventMode", "continuousTimeMode"])
def test_a_model_exchange_state_forged_into_a_co_simulation_phase_is_refused(make, kinds_states, source, state):
    """A Model Exchange model in stepComplete or stepFailed (the phases of
    a Co-Simulation instance) is not a state any instance can be in: the
    bytes must be refused (restored, the Model Exchange instance would be
    in stepComplete without a simulator, where fmi2DoStep is allowed)."""
    forged = forge(kinds_states[source], state)
    inst = make(fmu_type=fmi2.MODEL_EXCHANGE)
    status, handle = inst.deserialize(forged)
    if status == OK:
        assert inst.lib.fmi2SetFMUstate(inst.c, handle) == OK
        restored = inst.machine_state()
        do_step = inst.lib.fmi2DoStep(inst.c, 0.0, 0.001, 1)
        pytest.fail(f"accepted: the Model Exchange instance is now in {restored}; fmi2DoStep then returns "
                    f"{fmi2.STATUS_NAMES[do_step]}: {inst.log.last()[2]}")
    assert status == ERROR and not handle.value
    message = inst.log.last()[2]
    assert message.startswith("fmi2DeSerializeFMUstate: invalid serialized FMU state: "), message
    assert inst.machine_state() == "instantiated"
