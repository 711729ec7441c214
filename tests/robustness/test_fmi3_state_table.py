"""Every FMI 3.0 function in every state: refused where the state table
forbids it, not refused where it allows it.

The cases are generated from the declarative table `ALLOWED` of
crates/tdvass-fmi3/src/states.rs (getters and setters share one row there,
which stands for all 13 value types); the table is first checked against
the independent restatement `EXPECTED` in the same file. They are run on
both kinds of instance: a Co-Simulation instance (fmi3InstantiateCoSimulation)
in the states below, and a Model Exchange instance
(fmi3InstantiateModelExchange) in Instantiated, Configuration Mode,
Initialization Mode, Event Mode, Continuous-Time Mode, Terminated and
Error. Each case brings a fresh instance of the real library into the
state:

- Instantiated, Configuration Mode, Initialization Mode, Step Mode,
  Terminated: through the life-cycle calls;
- Step Mode after a discarded step: a real divergence (an unstable g makes
  fmi3DoStep return fmi3Discard);
- Intermediate Update Mode: the call is made from inside the
  intermediateUpdate callback of a real fmi3DoStep;
- Event Mode, Continuous-Time Mode: fmi3ExitInitializationMode of a Model
  Exchange instance, then fmi3EnterContinuousTimeMode;
- Error: a serialized Step Mode (Event Mode) state whose phase byte is set
  to Error (the library reaches Error only when the solver itself fails);
- Fatal only through an internal panic (covered by the unit tests of
  crates/tdvass-fmi3/src/ffi.rs); a forged Fatal state is refused below.

A refused call must return fmi3Error, log "fmi3X: not allowed in state Y"
and nothing else, and change nothing: the instance stays in Y and its
serialized state (phase, settings, simulation) is bit-identical before and
after (inside an intermediate update: the step ends where a step without
the call ends). An allowed call, made with valid arguments, must succeed on
the kind of instance it belongs to; a Model Exchange function on a
Co-Simulation instance (or the reverse) in a state both share may be
refused by the instance (fmi3Error, a reason), never with fmi3Fatal.
"""

import re
from ctypes import byref, c_bool, c_char, c_double, c_int, c_int32, c_size_t, c_uint32, c_void_p

import pytest

import fmi3
from fmi2 import array
from fmi3 import ERROR, OK, WARNING

STATE_NAMES = {
    "instantiated": "Instantiated",
    "configuration": "Configuration Mode",
    "initialization": "Initialization Mode",
    "step": "Step Mode",
    "discarded": "Step Mode after a discarded step",
    "intermediate": "Intermediate Update Mode",
    "terminated": "Terminated",
    "error": "Error",
    "fatal": "Fatal",
    "event": "Event Mode",
    "continuous": "Continuous-Time Mode",
}
REACHABLE_BY_KIND = {
    "cs": ["instantiated", "configuration", "initialization", "step", "discarded", "intermediate", "terminated",
           "error"],
    "me": ["instantiated", "configuration", "initialization", "event", "continuous", "terminated", "error"],
}
REACHABLE = [s for s in STATE_NAMES if s != "fatal"]
MODEL_EXCHANGE_FUNCTIONS = {
    "fmi3EnterEventMode", "fmi3UpdateDiscreteStates", "fmi3EnterContinuousTimeMode", "fmi3CompletedIntegratorStep",
    "fmi3SetTime", "fmi3SetContinuousStates", "fmi3GetContinuousStateDerivatives", "fmi3GetEventIndicators",
    "fmi3GetContinuousStates", "fmi3GetNominalsOfContinuousStates", "fmi3GetNumberOfEventIndicators",
    "fmi3GetNumberOfContinuousStates",
}
CO_SIMULATION_FUNCTIONS = {"fmi3GetOutputDerivatives", "fmi3DoStep"}
VALUE_TYPES = ["Float32", "Float64", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64",
               "Boolean", "String", "Binary"]


def allowed_table() -> dict[str, set[str]]:
    """fmi3 function -> the states (keys of STATE_NAMES) it is allowed in,
    read from the declarative table of states.rs."""
    source = fmi3.STATES_RS.read_text()
    by_variant = {variant: name for variant, name in re.findall(r'Fmi3Phase::(\w+) => "([^"]+)"', source)}
    short = {name: key for key, name in STATE_NAMES.items()}
    aliases = {}
    for part in re.search(r"use Fmi3Phase::\{(.*?)\};", source, re.S).group(1).split(","):
        m = re.fullmatch(r"(\w+)(?:\s+as\s+(\w+))?", part.strip())
        if m:
            aliases[m.group(2) or m.group(1)] = short[by_variant[m.group(1)]]

    def states(listed: str) -> set[str]:
        return {aliases[s.strip()] for s in listed.split(",") if s.strip()}

    sets = {name: states(listed)
            for name, listed in re.findall(r"const (\w+): PhaseSet = PhaseSet::of\(&\[([^\]]*)\]\);", source)}
    c_names = dict(re.findall(r'^\s*(\w+) => "(fmi3\w+)"', source, re.M))
    block = source[source.index("pub const ALLOWED") :]
    block = block[block.index("use Function::*;") : block.index("\n};")]
    table = {}
    for function, allowed in re.findall(r"\(\s*(\w+(?:\(ValueType::\w+\))?),\s*(PhaseSet::of\(&\[[^\]]*\]\)|\w+)",
                                        block):
        listed = sets[allowed] if allowed in sets else states(allowed[len("PhaseSet::of(&[") : -2])
        if function.startswith(("Get(", "Set(")):
            for t in VALUE_TYPES:
                table[f"fmi3{function[:3]}{t}"] = listed
        else:
            table[c_names[function]] = listed
    return table


TABLE = allowed_table()


def test_the_table_is_the_restated_one():
    """The parsed table agrees with the restatement the unit tests check
    (so the parsing is right), and covers the functions it should."""
    source = fmi3.STATES_RS.read_text()
    block = source[source.index("const EXPECTED") :]
    # Rows of 9 columns (up to Fatal) or 11 (with Event and Continuous-Time Mode).
    rows = dict(re.findall(r'\("(fmi3\w+)",\s*"([x.]{11}|[x.]{9})"\)', block[: block.index("];")]))
    assert len(rows) == 31, rows
    for function, row in rows.items():
        restated = {s for s, mark in zip(STATE_NAMES, row) if mark == "x"}
        assert {s for s in TABLE[function] if list(STATE_NAMES).index(s) < len(row)} == restated, function
    # The 12 Model Exchange functions, fmi3DoStep, and the partial derivatives
    # and dependencies, which Model Exchange may ask for in Event and
    # Continuous-Time Mode.
    assert sum(len(row) == 11 for row in rows.values()) == 16
    assert len(TABLE) == 32 + 2 * len(VALUE_TYPES)
    assert set(TABLE) <= set(fmi3.exported_functions())
    assert MODEL_EXCHANGE_FUNCTIONS <= set(TABLE) and CO_SIMULATION_FUNCTIONS <= set(TABLE)


CASES = [(k, f, s) for k, states in REACHABLE_BY_KIND.items() for f in sorted(TABLE) for s in states]
REFUSED = [(k, f, s) for k, f, s in CASES if s not in TABLE[f]]
ALLOWED = [(k, f, s) for k, f, s in CASES if s in TABLE[f] and f != "fmi3FreeInstance"]


def test_the_generated_cases_cover_the_table():
    # 58 functions (the 13 value types' getters and setters, 32 others) in
    # 8 states of a Co-Simulation instance and 7 of a Model Exchange one;
    # fmi3FreeInstance (allowed in every state but the intermediate update)
    # is checked on its own.
    assert len(TABLE) == 58
    assert len(CASES) == 58 * (8 + 7)
    refused = {kind: sum(1 for k, _, _ in REFUSED if k == kind) for kind in REACHABLE_BY_KIND}
    # Co-Simulation: the 118 refusals of before Model Exchange, and the 12
    # Model Exchange functions in each of the 8 states but where the table
    # lets Terminated and Error read the model (6 each) and Configuration
    # and Initialization Mode ask its sizes (2 each).
    assert refused["cs"] == 118 + 12 * 8 - 6 - 6 - 2 - 2, refused
    assert len(ALLOWED) == len(CASES) - len(REFUSED) - 7 - 7


# --------------------------------------------------------------- the states


# Phase codes in serialized states (tdvass_fmu::Phase).
PHASE_CODES = {"instantiated": 0, "initialization": 1, "step": 2, "discarded": 3, "terminated": 4, "error": 5,
               "fatal": 6, "event": 7, "continuous": 8}


def forge(data: bytes, state: str) -> bytes:
    """A serialized state with its phase byte set to `state`'s code."""
    data = bytearray(data)
    at, _ = fmi3.serialized_fields(bytes(data))
    data[at] = PHASE_CODES[state]
    return fmi3.reseal(data)


@pytest.fixture(scope="module")
def kinds_states(lib3):
    """Serialized states: Co-Simulation in Step Mode, Model Exchange in
    Event Mode and in Continuous-Time Mode."""
    inst = fmi3.Instance(lib3)
    inst.initialize(stop=15.0)
    assert inst.step(0.01) == OK
    step = inst.snapshot()
    inst.free()
    me = fmi3.Instance(lib3, model_exchange=True)
    me.initialize_model_exchange(stop=15.0)
    event = me.snapshot()
    assert me.enter_continuous_time_mode() == OK
    assert me.euler_step(1e-4)[0] == OK
    continuous = me.snapshot()
    me.free()
    states = {"step": step, "event": event, "continuous": continuous}
    for state, data in states.items():
        assert data[fmi3.serialized_fields(data)[0]] == PHASE_CODES[state]
    return states


@pytest.fixture(scope="module")
def error_state(kinds_states):
    """Serialized states with their phase byte set to Error: of a
    Co-Simulation instance (from Step Mode) and of a Model Exchange one
    (from Event Mode), by kind."""
    return {"cs": forge(kinds_states["step"], "error"), "me": forge(kinds_states["event"], "error")}


# Variables to read or write, by value type and state (None: an empty call,
# which is valid in every state where the function is allowed): in
# Configuration Mode only structural parameters are accessible, inside an
# intermediate update only the variables marked intermediateUpdate.
GET = {"Float64": "x_s", "Int32": "road_seed", "Int64": "variant", "UInt64": "root_count", "Boolean": "stable"}
SET = {"Float64": "g", "Int32": "road_seed", "Int64": "variant", "UInt64": "root_count"}
START = {"g": 5386.0, "road_seed": 1, "variant": 3, "root_count": 3, "x_g": 0.0}


def value_variable(function, state):
    kind = function[len("fmi3Get") :]
    if function.startswith("fmi3Get"):
        name = GET.get(kind)
        if state == "configuration":
            return name if name == "root_count" else None
        if state == "intermediate":
            return name if name == "x_s" else None
        return name
    if state == "configuration":
        return "root_count" if kind == "UInt64" else None
    if state == "intermediate":
        return "x_g" if kind == "Float64" else None
    if state in ("step", "event"):
        return "g" if kind == "Float64" else None  # the others are fixed
    if state == "continuous":
        return "x_g" if kind == "Float64" else None  # the input (road = 0); g only in Event Mode
    if kind == "UInt64":
        return None  # structural: Configuration Mode only
    return SET.get(kind)


def dependencies(vr):
    structure = fmi3.model_description()
    m = re.search(rf'<Output valueReference="{vr}" dependencies="([\d ]*)"', structure)
    return [int(d) for d in m.group(1).split()]


def call(inst, function, state):
    """`function` with valid arguments (for `state`); its status (None for
    fmi3FreeInstance)."""
    lib, c, vr = inst.lib, inst.c, inst.vr
    out = (c_double * 8)()
    size = c_size_t()
    value_type = function[len("fmi3Get") :]
    if value_type in VALUE_TYPES:
        name = value_variable(function, state)
        vrs = [vr[name]] if name else []
        if value_type == "Binary":
            return getattr(lib, function)(c, None, 0, None, None, 0)
        if function.startswith("fmi3Get"):
            return inst.get_values(function, vrs)[0]
        return inst.set_values(function, vrs, [START[name]] if name else [])
    tdd = vr["tire_deflection"]
    n_deps = len(dependencies(tdd))
    x_s = array(c_uint32, [vr["x_s"]])
    calls = {
        "fmi3SetDebugLogging": lambda: lib.fmi3SetDebugLogging(c, False, 0, None),
        "fmi3FreeInstance": lambda: lib.fmi3FreeInstance(c),
        "fmi3EnterInitializationMode": lambda: lib.fmi3EnterInitializationMode(c, False, 0.0, 0.0, True, 15.0),
        "fmi3ExitInitializationMode": lambda: lib.fmi3ExitInitializationMode(c),
        "fmi3Terminate": lambda: lib.fmi3Terminate(c),
        "fmi3Reset": lambda: lib.fmi3Reset(c),
        "fmi3GetNumberOfVariableDependencies": lambda: lib.fmi3GetNumberOfVariableDependencies(c, tdd, byref(size)),
        "fmi3GetVariableDependencies": lambda: lib.fmi3GetVariableDependencies(
            c, tdd, (c_size_t * n_deps)(), (c_uint32 * n_deps)(), (c_size_t * n_deps)(), (c_int * n_deps)(), n_deps
        ),
        "fmi3GetFMUState": lambda: lib.fmi3GetFMUState(c, byref(c_void_p())),
        "fmi3SetFMUState": lambda: lib.fmi3SetFMUState(c, inst.saved),
        "fmi3FreeFMUState": lambda: lib.fmi3FreeFMUState(c, byref(c_void_p(inst.saved.value))),
        "fmi3SerializedFMUStateSize": lambda: lib.fmi3SerializedFMUStateSize(c, inst.saved, byref(size)),
        "fmi3SerializeFMUState": lambda: lib.fmi3SerializeFMUState(
            c, inst.saved, (c_char * len(inst.saved_bytes))(), len(inst.saved_bytes)
        ),
        "fmi3DeserializeFMUState": lambda: lib.fmi3DeserializeFMUState(
            c, (c_char * len(inst.saved_bytes)).from_buffer_copy(inst.saved_bytes), len(inst.saved_bytes),
            byref(c_void_p()),
        ),
        "fmi3GetDirectionalDerivative": lambda: lib.fmi3GetDirectionalDerivative(
            c, x_s, 1, x_s, 1, array(c_double, [1.0]), 1, out, 1
        ),
        "fmi3GetAdjointDerivative": lambda: lib.fmi3GetAdjointDerivative(
            c, x_s, 1, x_s, 1, array(c_double, [1.0]), 1, out, 1
        ),
        "fmi3EnterConfigurationMode": lambda: lib.fmi3EnterConfigurationMode(c),
        "fmi3ExitConfigurationMode": lambda: lib.fmi3ExitConfigurationMode(c),
        "fmi3GetOutputDerivatives": lambda: lib.fmi3GetOutputDerivatives(c, x_s, 1, array(c_int32, [1]), out, 1),
        "fmi3DoStep": lambda: lib.fmi3DoStep(
            c, inst.time, 0.001, False, byref(c_bool()), byref(c_bool()), byref(c_bool()), byref(c_double())
        ),
        "fmi3EnterEventMode": lambda: lib.fmi3EnterEventMode(c),
        "fmi3UpdateDiscreteStates": lambda: lib.fmi3UpdateDiscreteStates(
            c, *[byref(c_bool()) for _ in range(5)], byref(c_double())
        ),
        "fmi3EnterContinuousTimeMode": lambda: lib.fmi3EnterContinuousTimeMode(c),
        "fmi3CompletedIntegratorStep": lambda: lib.fmi3CompletedIntegratorStep(
            c, True, byref(c_bool()), byref(c_bool())
        ),
        "fmi3SetTime": lambda: lib.fmi3SetTime(c, inst.time),
        # Zeros: valid continuous states (those of the start).
        "fmi3SetContinuousStates": lambda: lib.fmi3SetContinuousStates(c, (c_double * fmi3.NX)(), fmi3.NX),
        "fmi3GetContinuousStateDerivatives": lambda: lib.fmi3GetContinuousStateDerivatives(
            c, (c_double * fmi3.NX)(), fmi3.NX
        ),
        "fmi3GetEventIndicators": lambda: lib.fmi3GetEventIndicators(c, out, fmi3.NZ),
        "fmi3GetContinuousStates": lambda: lib.fmi3GetContinuousStates(c, (c_double * fmi3.NX)(), fmi3.NX),
        "fmi3GetNominalsOfContinuousStates": lambda: lib.fmi3GetNominalsOfContinuousStates(
            c, (c_double * fmi3.NX)(), fmi3.NX
        ),
        "fmi3GetNumberOfEventIndicators": lambda: lib.fmi3GetNumberOfEventIndicators(c, byref(size)),
        "fmi3GetNumberOfContinuousStates": lambda: lib.fmi3GetNumberOfContinuousStates(c, byref(size)),
    }
    return calls[function]()


def keep_a_state(inst):
    status, inst.saved = inst.get_state()
    assert status == OK, inst.log.last()
    inst.saved_bytes = inst.serialize(inst.saved)


def bring_to(make3, error_state, state, kind="cs"):
    inst = make3(model_exchange=kind == "me")
    if state == "configuration":
        assert inst.lib.fmi3EnterConfigurationMode(inst.c) == OK
    elif state == "initialization":
        assert inst.enter(0.0, 15.0) == OK
    elif kind == "me" and state in ("event", "continuous", "terminated"):
        # Continuous-Time Mode: with the road as input (the setter there).
        inst.initialize(stop=15.0, **({"road": 0} if state == "continuous" else {}))
        if state == "continuous":
            assert inst.enter_continuous_time_mode() == OK
        if state == "terminated":
            assert inst.lib.fmi3Terminate(inst.c) == OK
    elif state in ("step", "terminated"):
        inst.initialize(stop=15.0)
        assert inst.step(0.01) == OK
        if state == "terminated":
            assert inst.lib.fmi3Terminate(inst.c) == OK
    elif state == "discarded":
        assert inst.initialize(g=-40000.0, tau=0.11, x_s_start=0.01) == WARNING
        while (status := inst.step(5.0)) == OK:
            assert inst.time < 3600, "never diverged"
        assert status == fmi3.DISCARD, inst.log.last()
    elif state == "error":
        status, forged = inst.deserialize(error_state[kind])
        assert status == OK, inst.log.last()
        assert inst.lib.fmi3SetFMUState(inst.c, forged) == OK
    assert inst.machine_state() == STATE_NAMES[state]
    keep_a_state(inst)
    return inst


def inside_an_intermediate_update(make3, action):
    """Runs `action(inst)` once, from the first intermediate update of a
    1 ms step (10 internal steps of 0.1 ms, max_internal_step) from t = 0
    in Step Mode. Returns the
    instance, what the action returned, what it logged, the state inside
    the callback after the action, and the serialized state after the step
    with the serialized state of the same step without the action."""
    seen = {}

    def on_update(inst, time, can_return_early):
        if "result" not in seen:
            assert inst.machine_state() == STATE_NAMES["intermediate"]
            before = len(inst.log.messages)
            seen["result"] = action(inst)
            seen["log"] = inst.log.since(before)
            seen["state"] = inst.machine_state()
        return False

    runs = []
    for act in (on_update, lambda *_: False):
        inst = make3(intermediate=act)
        inst.initialize(stop=15.0, max_internal_step=1e-4)
        keep_a_state(inst)
        assert inst.step(0.001) == OK, inst.log.last()
        assert len(inst.updates) == 9  # the nodes inside the step
        runs.append(inst)
    assert "result" in seen
    return runs[0], seen["result"], seen["log"], seen["state"], runs[0].snapshot(), runs[1].snapshot()


def refusal(function, state):
    return [(ERROR, "logStatusError", f"{function}: not allowed in state {STATE_NAMES[state]}")]


def belongs_to(function, kind):
    """Whether `function` is one of the instance kind's own (or common)."""
    return function not in (MODEL_EXCHANGE_FUNCTIONS if kind == "cs" else CO_SIMULATION_FUNCTIONS)


@pytest.mark.parametrize("kind, function, state", REFUSED, ids=[f"{k}-{f}-in-{s}" for k, f, s in REFUSED])
def test_call_in_a_state_where_it_is_not_allowed(make3, error_state, kind, function, state):
    if state == "intermediate":
        inst, status, log, after, snapshot, clean = inside_an_intermediate_update(
            make3, lambda i: call(i, function, state)
        )
        assert status == (None if function == "fmi3FreeInstance" else ERROR)
        assert log == refusal(function, state)
        assert after == STATE_NAMES[state]
        assert snapshot == clean
        # The FMU state kept before the step is still there.
        assert inst.serialize(inst.saved) == inst.saved_bytes
        return
    inst = bring_to(make3, error_state, state, kind)
    before = inst.snapshot()
    count = len(inst.log.messages)
    assert call(inst, function, state) == ERROR
    assert inst.log.since(count) == refusal(function, state)
    assert inst.machine_state() == STATE_NAMES[state]
    assert inst.snapshot() == before


@pytest.mark.parametrize("kind, function, state", ALLOWED, ids=[f"{k}-{f}-in-{s}" for k, f, s in ALLOWED])
def test_call_in_a_state_where_it_is_allowed(make3, error_state, kind, function, state):
    if state == "intermediate":
        _, status, log, after, _, _ = inside_an_intermediate_update(make3, lambda i: call(i, function, state))
        assert status == OK, log
        assert after == STATE_NAMES[state]
        return
    inst = bring_to(make3, error_state, state, kind)
    count = len(inst.log.messages)
    status = call(inst, function, state)
    log = inst.log.since(count)
    assert status != fmi3.FATAL, log
    assert not [m for m in log if "not allowed in state" in m[2] or m[0] == fmi3.FATAL], log
    if belongs_to(function, kind):
        assert status == OK, log
    else:
        # Refused by the instance, with a reason naming the function.
        assert status in (OK, ERROR), log
        if status == ERROR:
            assert [m[0] for m in log] == [ERROR] and log[0][2].startswith(f"{function}: "), log
            assert inst.machine_state() == STATE_NAMES[state]


@pytest.mark.parametrize("kind, state", [(k, s) for k, states in REACHABLE_BY_KIND.items() for s in states])
def test_free_instance_is_allowed_in_every_state_but_the_intermediate_update(make3, error_state, kind, state):
    if state == "intermediate":
        return  # refused: test_call_in_a_state_where_it_is_not_allowed
    inst = bring_to(make3, error_state, state, kind)
    count = len(inst.log.messages)
    inst.free()
    assert not inst.c
    assert not [m for m in inst.log.since(count) if m[0] != OK], inst.log.since(count)


def test_a_forged_fatal_state_is_refused(make3, error_state):
    """Fatal cannot be reached through a serialized state."""
    data = bytearray(error_state["cs"])
    at, _ = fmi3.serialized_fields(error_state["cs"])
    data[at] = 6  # Fatal
    inst = make3()
    status, state = inst.deserialize(fmi3.reseal(data))
    assert status == ERROR and not state.value
    assert inst.log.last()[2] == "fmi3DeserializeFMUState: invalid serialized FMU state: phase code 6"
    assert inst.machine_state() == "Instantiated"


def test_restoring_a_step_mode_state_ends_configuration_mode(initialized3):
    """An FMU state does not hold Configuration Mode: restoring a Step Mode
    state there puts the instance in Step Mode with every variable
    accessible (it used to stay half in Configuration Mode, refusing every
    variable but the structural parameters)."""
    inst = initialized3()
    assert inst.step(0.1) == OK
    x_s = inst.get("x_s")
    status, state = inst.get_state()
    assert inst.lib.fmi3Reset(inst.c) == OK
    assert inst.lib.fmi3EnterConfigurationMode(inst.c) == OK
    assert inst.lib.fmi3SetFMUState(inst.c, state) == OK
    assert inst.machine_state() == "Step Mode"
    assert inst.get("x_s") == x_s
    assert inst.get_values("fmi3GetInt64", [inst.vr["variant"]]) == (OK, [3])
    assert inst.step(0.1, t=0.1) == OK
    # An Instantiated state restored in Configuration Mode stays there.
    assert inst.lib.fmi3Reset(inst.c) == OK
    status, instantiated = inst.get_state()
    assert inst.lib.fmi3EnterConfigurationMode(inst.c) == OK
    assert inst.lib.fmi3SetFMUState(inst.c, instantiated) == OK
    assert inst.machine_state() == "Configuration Mode"


# ----------------------------------------------- FMU states across the kinds


@pytest.mark.parametrize("state", ["event", "continuous"])
def test_a_model_exchange_state_restores_only_into_a_model_exchange_instance(make3, kinds_states, state):
    data = kinds_states[state]
    me = make3(model_exchange=True)
    status, handle = me.deserialize(data)
    assert status == OK, me.log.last()
    assert me.lib.fmi3SetFMUState(me.c, handle) == OK
    assert me.machine_state() == STATE_NAMES[state]
    assert me.snapshot() == data
    cs = make3()
    for setup in (lambda: None, lambda: cs.initialize(stop=15.0)):
        setup()
        before = cs.snapshot()
        status, handle = cs.deserialize(data)
        assert status == ERROR and not handle.value
        assert cs.log.last() == (ERROR, "logStatusError", "fmi3DeserializeFMUState: a Model Exchange state cannot "
                                                          "be restored into a Co-Simulation instance")
        assert cs.snapshot() == before


def test_a_co_simulation_state_restores_only_into_a_co_simulation_instance(make3, kinds_states):
    me = make3(model_exchange=True)
    status, handle = me.deserialize(kinds_states["step"])
    assert status == ERROR and not handle.value
    assert me.log.last() == (ERROR, "logStatusError", "fmi3DeserializeFMUState: a Co-Simulation state cannot be "
                                                      "restored into a Model Exchange instance")
    assert me.machine_state() == "Instantiated"


@pytest.mark.parametrize("state", ["event", "continuous"])
def test_a_co_simulation_state_forged_into_a_model_exchange_phase_is_refused(make3, kinds_states, state):
    forged = forge(kinds_states["step"], state)
    for model_exchange in (False, True):
        inst = make3(model_exchange=model_exchange)
        status, handle = inst.deserialize(forged)
        assert status == ERROR and not handle.value
        message = inst.log.last()[2]
        assert message.startswith("fmi3DeserializeFMUState: invalid serialized FMU state: "), message


@pytest.mark.parametrize("state", ["step", "discarded"])
@pytest.mark.parametrize("source", ["event", "continuous"])
def test_a_model_exchange_state_forged_into_a_co_simulation_phase_is_refused(make3, kinds_states, source, state):
    """A Model Exchange model in Step Mode (or after a discarded step) is
    not a state any instance can be in: the bytes must be refused."""
    inst = make3(model_exchange=True)
    status, handle = inst.deserialize(forge(kinds_states[source], state))
    if status == OK:
        assert inst.lib.fmi3SetFMUState(inst.c, handle) == OK
        restored = inst.machine_state()
        result = inst.do_step(0.0, 0.001)[0]
        pytest.fail(f"accepted: the Model Exchange instance is now in {restored}; fmi3DoStep then returns "
                    f"{fmi3.STATUS_NAMES[result]}: {inst.log.last()[2]}")
    assert status == ERROR and not handle.value
    assert inst.log.last()[2].startswith("fmi3DeserializeFMUState: invalid serialized FMU state: ")
