"""Every FMI 3.0 function in every state: refused where the state table
forbids it, not refused where it allows it.

The cases are generated from the declarative table `ALLOWED` of
crates/tdvass-fmi3/src/states.rs (getters and setters share one row there,
which stands for all 13 value types); the table is first checked against
the independent restatement `EXPECTED` in the same file. Each case brings a
fresh instance of the real library into the state:

- Instantiated, Configuration Mode, Initialization Mode, Step Mode,
  Terminated: through the life-cycle calls;
- Step Mode after a discarded step: a real divergence (an unstable g makes
  fmi3DoStep return fmi3Discard);
- Intermediate Update Mode: the call is made from inside the
  intermediateUpdate callback of a real fmi3DoStep;
- Error: a serialized Step Mode state whose phase byte is set to Error
  (the library reaches Error only when the solver itself fails);
- Fatal only through an internal panic (covered by the unit tests of
  crates/tdvass-fmi3/src/ffi.rs); a forged Fatal state is refused below.

A refused call must return fmi3Error, log "fmi3X: not allowed in state Y"
and nothing else, and change nothing: the instance stays in Y and its
serialized state (phase, settings, simulation) is bit-identical before and
after (inside an intermediate update: the step ends where a step without
the call ends). An allowed call, made with valid arguments, must succeed.
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
}
REACHABLE = [s for s in STATE_NAMES if s != "fatal"]
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
    rows = dict(re.findall(r'\("(fmi3\w+)",\s*"([x.]{9})"\)', block[: block.index("];")]))
    assert len(rows) == 19, rows
    for function, row in rows.items():
        assert TABLE[function] == {s for s, mark in zip(STATE_NAMES, row) if mark == "x"}, function
    assert len(TABLE) == 20 + 2 * len(VALUE_TYPES)
    assert set(TABLE) <= set(fmi3.exported_functions())


CASES = [(f, s) for f in sorted(TABLE) for s in REACHABLE]
REFUSED = [(f, s) for f, s in CASES if s not in TABLE[f]]
ALLOWED = [(f, s) for f, s in CASES if s in TABLE[f] and f != "fmi3FreeInstance"]


def test_the_generated_cases_cover_the_table():
    # 46 functions in 8 reachable states: 118 refusals; fmi3FreeInstance
    # (allowed in 7 of them) is checked on its own.
    assert len(CASES) == 368
    assert len(REFUSED) == 118
    assert len(ALLOWED) == 368 - 118 - 7


# --------------------------------------------------------------- the states


@pytest.fixture(scope="module")
def error_state(lib3):
    """A serialized Step Mode state with its phase byte set to Error."""
    inst = fmi3.Instance(lib3)
    inst.initialize(stop=15.0)
    assert inst.step(0.01) == OK
    data = bytearray(inst.snapshot())
    inst.free()
    at, _ = fmi3.serialized_fields(bytes(data))
    assert data[at] == 2  # the phase code of Step Mode
    data[at] = 5  # Error
    return fmi3.reseal(data)


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
    if state == "step":
        return "g" if kind == "Float64" else None  # the others are fixed
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
    }
    return calls[function]()


def keep_a_state(inst):
    status, inst.saved = inst.get_state()
    assert status == OK, inst.log.last()
    inst.saved_bytes = inst.serialize(inst.saved)


def bring_to(make3, error_state, state):
    inst = make3()
    if state == "configuration":
        assert inst.lib.fmi3EnterConfigurationMode(inst.c) == OK
    elif state == "initialization":
        assert inst.enter(0.0, 15.0) == OK
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
        status, forged = inst.deserialize(error_state)
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


@pytest.mark.parametrize("function, state", REFUSED, ids=[f"{f}-in-{s}" for f, s in REFUSED])
def test_call_in_a_state_where_it_is_not_allowed(make3, error_state, function, state):
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
    inst = bring_to(make3, error_state, state)
    before = inst.snapshot()
    count = len(inst.log.messages)
    assert call(inst, function, state) == ERROR
    assert inst.log.since(count) == refusal(function, state)
    assert inst.machine_state() == STATE_NAMES[state]
    assert inst.snapshot() == before


@pytest.mark.parametrize("function, state", ALLOWED, ids=[f"{f}-in-{s}" for f, s in ALLOWED])
def test_call_in_a_state_where_it_is_allowed(make3, error_state, function, state):
    if state == "intermediate":
        _, status, log, after, _, _ = inside_an_intermediate_update(make3, lambda i: call(i, function, state))
        assert status == OK, log
        assert after == STATE_NAMES[state]
        return
    inst = bring_to(make3, error_state, state)
    count = len(inst.log.messages)
    status = call(inst, function, state)
    assert status == OK, inst.log.since(count)
    assert not [m for m in inst.log.since(count) if "not allowed in state" in m[2]]


@pytest.mark.parametrize("state", REACHABLE)
def test_free_instance_is_allowed_in_every_state_but_the_intermediate_update(make3, error_state, state):
    if state == "intermediate":
        return  # refused: test_call_in_a_state_where_it_is_not_allowed
    inst = bring_to(make3, error_state, state)
    count = len(inst.log.messages)
    inst.free()
    assert not inst.c
    assert not [m for m in inst.log.since(count) if m[0] != OK], inst.log.since(count)


def test_a_forged_fatal_state_is_refused(make3, error_state):
    """Fatal cannot be reached through a serialized state."""
    data = bytearray(error_state)
    at, _ = fmi3.serialized_fields(error_state)
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
