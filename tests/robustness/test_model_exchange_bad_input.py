"""Model Exchange through the real shared libraries, FMI 2.0 and FMI 3.0
alike (each test runs on both): the life cycle through Event Mode and
Continuous-Time Mode, then bad input to every Model Exchange function:
NULL pointers, wrong numbers of states and indicators, NaN and infinite
states, times not finite, beyond what the model resolves, needing too many
road nodes or set back before the floor (the last completed integrator step
or event, or 1 s before the latest time for a master that never completes
a step), calls in the wrong state. Going back within reach gives the same
bits as never having looked ahead. Every refusal must return the Error
status, log one line naming the function and the argument or value, change
nothing (the serialized state is bit-identical before and after) and leave
the instance usable. A diverging state asks the master to terminate.

The corner and the chassis (their own FMUs, the same library) get the same:
non-finite states, times, body inputs, x_g and forces, a non-positive mass
or inertia, each refused naming the value; their FMU states restore a run
to the bit.

One file for the whole Model Exchange surface on purpose (the fixtures load
both libraries once): hence its length."""

import math
import resource
from ctypes import byref, c_bool, c_double, c_int, c_size_t, c_uint8
from decimal import Decimal

import pytest
from conftest import rust

import fmi2
import fmi3
from fmi2 import NX, NZ, STATE_NAMES, array

OK, WARNING, ERROR, FATAL = 0, 1, 3, 4  # the same codes in both versions
NAN, INF = float("nan"), float("inf")

FUNCTIONS = {
    "fmi2": {
        "set_time": "fmi2SetTime", "set_states": "fmi2SetContinuousStates", "derivatives": "fmi2GetDerivatives",
        "indicators": "fmi2GetEventIndicators", "states": "fmi2GetContinuousStates",
        "nominals": "fmi2GetNominalsOfContinuousStates", "event": "fmi2EnterEventMode",
        "continuous": "fmi2EnterContinuousTimeMode", "completed": "fmi2CompletedIntegratorStep",
        "discrete": "fmi2NewDiscreteStates", "do_step": "fmi2DoStep", "terminate": "fmi2Terminate",
        "deserialize": "fmi2DeSerializeFMUstate",
    },
    "fmi3": {
        "set_time": "fmi3SetTime", "set_states": "fmi3SetContinuousStates",
        "derivatives": "fmi3GetContinuousStateDerivatives", "indicators": "fmi3GetEventIndicators",
        "states": "fmi3GetContinuousStates", "nominals": "fmi3GetNominalsOfContinuousStates",
        "event": "fmi3EnterEventMode", "continuous": "fmi3EnterContinuousTimeMode",
        "completed": "fmi3CompletedIntegratorStep", "discrete": "fmi3UpdateDiscreteStates", "do_step": "fmi3DoStep",
        "terminate": "fmi3Terminate", "deserialize": "fmi3DeserializeFMUState",
    },
}
# The names of the array arguments (as the refusals name them).
ARRAYS = {
    "fmi2": {"set_states": "x", "derivatives": "derivatives", "indicators": "eventIndicators", "states": "x",
             "nominals": "x_nominal"},
    "fmi3": {"set_states": "continuousStates", "derivatives": "derivatives", "indicators": "eventIndicators",
             "states": "continuousStates", "nominals": "nominals"},
}
STATES = {
    "fmi2": {"instantiated": "instantiated", "initialization": "initializationMode", "event": "eventMode",
             "continuous": "continuousTimeMode", "terminated": "terminated"},
    "fmi3": {"instantiated": "Instantiated", "initialization": "Initialization Mode", "event": "Event Mode",
             "continuous": "Continuous-Time Mode", "terminated": "Terminated"},
}
# What a wrong count is called in the refusal, and the right count.
COUNTS = {"derivatives": ("derivatives", NX), "states": ("continuous states", NX), "nominals": ("nominals", NX),
          "indicators": ("event indicators", NZ)}


class ModelExchange:
    """One FMI version's Model Exchange, spelled alike for the tests."""

    def __init__(self, version, make):
        self.version = version
        self.make = make
        self.fn = FUNCTIONS[version]
        self.array_name = ARRAYS[version]
        self.state_name = STATES[version]

    def __repr__(self):
        return self.version

    def instance(self, **kwargs):
        if self.version == "fmi2":
            return self.make(fmu_type=fmi2.MODEL_EXCHANGE, **kwargs)
        return self.make(model_exchange=True, **kwargs)

    def initialization_mode(self, inst):
        if self.version == "fmi2":
            assert inst.setup(0.0, 15.0) == OK and inst.enter() == OK
        else:
            assert inst.enter(0.0, 15.0) == OK
        assert inst.machine_state() == self.state_name["initialization"]

    def event_mode(self, stop=15.0, **values):
        """An instance in Event Mode at t = 0."""
        inst = self.instance()
        assert inst.initialize_model_exchange(stop=stop, **values) == OK
        return inst

    def continuous_time_mode(self, steps=0, h=1e-4, **values):
        """An instance in Continuous-Time Mode after `steps` completed Euler
        steps of h from t = 0."""
        inst = self.event_mode(**values)
        assert self.discrete(inst)[0] == OK
        assert inst.enter_continuous_time_mode() == OK
        for _ in range(steps):
            assert inst.euler_step(h) == (OK, 0, 0), inst.log.last()
        return inst

    def call(self, inst, key, *args):
        return getattr(inst.lib, self.fn[key])(inst.c, *args)

    def discrete(self, inst):
        """The event update: (status, terminateSimulation, every flag and the
        next event time as the FMU wrote them)."""
        if self.version == "fmi2":
            status, info = inst.new_discrete_states()
            flags = (info.newDiscreteStatesNeeded, info.terminateSimulation, info.nominalsOfContinuousStatesChanged,
                     info.valuesOfContinuousStatesChanged, info.nextEventTimeDefined, info.nextEventTime)
            return status, info.terminateSimulation, flags
        status, *flags = inst.update_discrete_states()
        return status, flags[1], tuple(flags)

    def do_step(self, inst, t, h):
        if self.version == "fmi2":
            return inst.lib.fmi2DoStep(inst.c, t, h, 1)
        return inst.do_step(t, h)[0]


@pytest.fixture(params=["fmi2", "fmi3"])
def me(request):
    """The Model Exchange of one FMI version (fixtures make/make3: every
    instance is freed after the test, and the library must still answer)."""
    make = request.getfixturevalue("make" if request.param == "fmi2" else "make3")
    return ModelExchange(request.param, make)


def last_error(inst):
    status, category, message = inst.log.last()
    assert status == ERROR and category == "logStatusError", inst.log.last()
    return message


def refused(me, inst, key, args, expected, state):
    """`key` called with `args` is refused: fmi2Error/fmi3Error, exactly one
    log line `<function>: <expected>`, the instance unchanged and still in
    `state`."""
    before = inst.snapshot()
    count = len(inst.log.messages)
    assert me.call(inst, key, *args) == ERROR
    assert inst.log.since(count) == [(ERROR, "logStatusError", f"{me.fn[key]}: {expected}")], inst.log.since(count)
    assert inst.machine_state() == me.state_name[state]
    assert inst.snapshot() == before


def vector(n, value=NAN):
    return (c_double * max(n, 1))(*([value] * max(n, 1)))


# --------------------------------------------------------------- life cycle


def test_life_cycle_through_event_and_continuous_time_mode(me):
    inst = me.instance()
    assert inst.ok
    assert inst.machine_state() == me.state_name["instantiated"]
    me.initialization_mode(inst)
    assert inst.exit() == OK, inst.log.last()
    assert inst.machine_state() == me.state_name["event"]
    # The event update at the start: nothing pending, no time event.
    status, terminate, flags = me.discrete(inst)
    assert status == OK and terminate == 0
    assert flags[:5] == (0, 0, 0, 0, 0) and flags[5] == 0.0, flags
    assert inst.enter_continuous_time_mode() == OK
    assert inst.machine_state() == me.state_name["continuous"]
    status, x = inst.continuous_states()
    assert status == OK and x == [0.0] * NX  # the default start values
    status, nominals = inst.nominals()
    assert status == OK and all(0 < v < math.inf for v in nominals), nominals
    status, z = inst.event_indicators()
    assert status == OK and z[0] > 0  # the tire in contact: a positive margin
    for _ in range(20):
        assert inst.euler_step(1e-4) == (OK, 0, 0), inst.log.last()
    status, x = inst.continuous_states()
    assert status == OK and any(x) and all(math.isfinite(v) for v in x)
    status, dx = inst.derivatives()
    assert status == OK and all(math.isfinite(v) for v in dx)
    assert inst.enter_event_mode() == OK
    assert inst.machine_state() == me.state_name["event"]
    assert me.discrete(inst)[:2] == (OK, 0)
    assert inst.enter_continuous_time_mode() == OK
    assert inst.euler_step(1e-4) == (OK, 0, 0)
    assert me.call(inst, "terminate") == OK
    assert inst.machine_state() == me.state_name["terminated"]
    # The model can still be read after terminating.
    assert inst.continuous_states()[0] == OK and inst.derivatives()[0] == OK
    # Nothing but the probes of machine_state() was refused.
    assert not [m for m in inst.log.messages if m[0] != OK and "CancelStep" not in m[2]
                and "ExitConfigurationMode" not in m[2]], inst.log.messages


def test_sizes_of_the_model_fmi3(make3):
    inst = make3(model_exchange=True)
    assert inst.number_of("ContinuousStates")[0] == ERROR
    assert last_error(inst) == "fmi3GetNumberOfContinuousStates: not allowed in state Instantiated"
    assert inst.enter(0.0, 15.0) == OK
    assert inst.number_of("ContinuousStates") == (OK, NX)
    assert inst.number_of("EventIndicators") == (OK, NZ)
    assert inst.lib.fmi3GetNumberOfContinuousStates(inst.c, None) == ERROR
    assert last_error(inst) == "fmi3GetNumberOfContinuousStates: nContinuousStates is NULL while its length is 1"
    assert inst.lib.fmi3GetNumberOfEventIndicators(inst.c, None) == ERROR
    assert last_error(inst) == "fmi3GetNumberOfEventIndicators: nEventIndicators is NULL while its length is 1"


# ------------------------------------------------------------ NULL pointers


@pytest.mark.parametrize("key", ["set_states", "derivatives", "indicators", "states", "nominals"])
def test_null_array_with_a_length(me, key):
    inst = me.continuous_time_mode(steps=2)
    n = NZ if key == "indicators" else NX
    refused(me, inst, key, (None, n), f"{me.array_name[key]} is NULL while its length is {n}", "continuous")
    assert inst.euler_step(1e-4) == (OK, 0, 0)  # still usable


def test_null_event_info_fmi2(model_exchange):
    me = ModelExchange("fmi2", None)
    inst = model_exchange()
    refused(me, inst, "discrete", (None,), "eventInfo is NULL while its length is 1", "event")
    assert me.discrete(inst)[:2] == (OK, 0)


UPDATE_FLAGS = ["discreteStatesNeedUpdate", "terminateSimulation", "nominalsOfContinuousStatesChanged",
                "valuesOfContinuousStatesChanged", "nextEventTimeDefined", "nextEventTime"]


@pytest.mark.parametrize("position", range(6), ids=UPDATE_FLAGS)
def test_null_out_pointers_of_update_discrete_states_fmi3(model_exchange3, position):
    me = ModelExchange("fmi3", None)
    inst = model_exchange3()
    outs = [c_uint8(0xAA) for _ in range(5)] + [c_double(-1.0)]
    args = [None if k == position else byref(out) for k, out in enumerate(outs)]
    refused(me, inst, "discrete", args, f"{UPDATE_FLAGS[position]} is NULL while its length is 1", "event")
    assert [o.value for o in outs] == [0xAA] * 5 + [-1.0]  # nothing written
    assert me.discrete(inst)[:2] == (OK, 0)


@pytest.mark.parametrize("position", [0, 1], ids=["enterEventMode", "terminateSimulation"])
def test_null_out_pointers_of_completed_integrator_step(me, position):
    inst = me.continuous_time_mode(steps=1)
    assert inst.set_time(2e-4) == OK
    flag = c_int(7) if me.version == "fmi2" else c_bool(True)
    args = [1, None, byref(flag)] if position == 0 else [1, byref(flag), None]
    name = ["enterEventMode", "terminateSimulation"][position]
    refused(me, inst, "completed", args, f"{name} is NULL while its length is 1", "continuous")
    # Not completed: the time can still go back to the last completed step.
    assert inst.set_time(1e-4) == OK
    assert inst.completed_integrator_step() == (OK, 0, 0)


# ------------------------------------------------------------ wrong counts


@pytest.mark.parametrize("n", [NX - 1, NX + 1, 0])
def test_wrong_number_of_continuous_states_given(me, n):
    inst = me.continuous_time_mode(steps=2)
    status, x = inst.continuous_states()
    values = array(c_double, (x + [0.0])[:n]) if n else None
    refused(me, inst, "set_states", (values, n), f"{n} continuous states given, the model has {NX}", "continuous")
    assert inst.continuous_states() == (OK, x)


@pytest.mark.parametrize("n", [NX - 1, NX + 1, 0])
@pytest.mark.parametrize("key", ["derivatives", "states", "nominals"])
def test_wrong_number_of_values_asked_for(me, key, n):
    inst = me.continuous_time_mode(steps=2)
    out = vector(n) if n else None
    what, expected = COUNTS[key]
    refused(me, inst, key, (out, n), f"{n} {what} asked for, the model has {expected}", "continuous")
    if n:
        assert all(math.isnan(v) for v in out), list(out)  # nothing written
    assert getattr(inst, {"derivatives": "derivatives", "states": "continuous_states",
                          "nominals": "nominals"}[key])()[0] == OK


@pytest.mark.parametrize("n", [0, 2])
def test_wrong_number_of_event_indicators_asked_for(me, n):
    inst = me.continuous_time_mode(steps=2)
    out = vector(n) if n else None
    refused(me, inst, "indicators", (out, n), f"{n} event indicators asked for, the model has {NZ}", "continuous")
    assert inst.event_indicators()[0] == OK


# ------------------------------------------------------- non-finite states


@pytest.mark.parametrize("index, value", [(0, NAN), (3, INF), (NX - 1, -INF)],
                         ids=["x_s-nan", "v_h-inf", "last-minus-inf"])
def test_non_finite_state_is_refused_naming_it(me, index, value):
    inst = me.continuous_time_mode(steps=2)
    status, x = inst.continuous_states()
    bad = list(x)
    bad[index] = value
    refused(me, inst, "set_states", (array(c_double, bad), NX),
            f"continuous state {index} (`{STATE_NAMES[index]}`) = {rust(value)} is not finite", "continuous")
    assert inst.continuous_states() == (OK, x)
    assert inst.euler_step(1e-4) == (OK, 0, 0)


def test_huge_finite_states_give_finite_derivatives_or_a_refusal(me):
    """States at the limit of a double: the derivatives are finite, or
    refused naming the derivative that is not; never a panic or a NaN."""
    inst = me.continuous_time_mode()
    assert inst.set_continuous_states([1e300] * NX) == OK
    count = len(inst.log.messages)
    status, dx = inst.derivatives()
    assert status in (OK, ERROR), inst.log.since(count)
    if status == OK:
        assert all(math.isfinite(v) for v in dx), dx
    else:
        message = last_error(inst)
        assert message.startswith(f"{me.fn['derivatives']}: the derivative of `"), message


# -------------------------------------------------------------------- time

TIME_RESOLUTION = 4398046511104.0  # 2^42: |t| is at most this many times the finest time resolved
LARGEST_STEP = 0.01  # the coarsest of the finest times (s)
MAX_ROAD_NODES = 4194304  # random-road nodes generated or kept per call
ISO_NODE_INTERVAL = 1e-3  # the ISO 8608 road's nodes (s)
DEFAULT_TAU = 0.0002  # the default delay: variant 3 keeps a history
# The roads, by the `road` parameter: 2 is an ISO 8608 class C road at 20 m/s.
ROADS = {0: {"road": 0}, 1: {"road": 1}, 2: {"road": 2, "road_class": 3, "vehicle_speed": 20.0}, 3: {"road": 3}}
RESOLVES = "2^42 times the finest time the model resolves (the delay, the road's node interval, 0.01 s)"


def rust_e(value: float) -> str:
    """`value` as Rust's `{:e}` prints an f64 (`8.796093022208e8`)."""
    _, digits, exponent = Decimal(repr(value)).normalize().as_tuple()
    mantissa = "".join(map(str, digits))
    mantissa = mantissa[0] + ("." + mantissa[1:] if len(mantissa) > 1 else "")
    return f"{mantissa}e{exponent + len(digits) - 1}"


def time_limit(variant=3, tau=DEFAULT_TAU, road=1, road_sample_interval=0.1, **_):
    """The largest |time| (s) SetTime takes: 2^42 times the finest time the
    model resolves (0.01 s, the delay of a history, the random road's node
    interval)."""
    finest = LARGEST_STEP
    if variant == 3 and tau >= 1e-7:
        finest = min(finest, tau)
    if road == 2:
        finest = min(finest, ISO_NODE_INTERVAL)
    elif road == 3:
        finest = min(finest, road_sample_interval)
    return finest * TIME_RESOLUTION


def node_interval(road=1, road_sample_interval=0.1, **_):
    return {2: ISO_NODE_INTERVAL, 3: road_sample_interval}.get(road)


def unresolved_message(time, limit):
    return f"time {rust(time)} s is not finite or beyond {rust_e(limit)} s, {RESOLVES}"


def floor_message(time, floor):
    return (f"time {rust(time)} s is before {rust(floor)} s, the last completed integrator step or event: "
            "no master goes back before it")


def refused_naming(me, inst, key, args, parts, state="continuous"):
    """As `refused`, for a message checked by the `parts` it contains: the
    Error status, exactly one log line `<function>: ...`, nothing changed.
    Returns the message."""
    before = inst.snapshot()
    count = len(inst.log.messages)
    assert me.call(inst, key, *args) == ERROR
    logged = inst.log.since(count)
    assert len(logged) == 1 and logged[0][:2] == (ERROR, "logStatusError"), logged
    message = logged[0][2]
    assert message.startswith(f"{me.fn[key]}: "), message
    for part in parts:
        assert part in message, (part, message)
    assert inst.machine_state() == me.state_name[state]
    assert inst.snapshot() == before
    return message


def test_time_before_the_last_completed_step_is_refused_naming_both_times(me):
    inst = me.continuous_time_mode()
    assert inst.set_time(1e-3) == OK
    assert inst.completed_integrator_step() == (OK, 0, 0)
    refused(me, inst, "set_time", (5e-4,), floor_message(5e-4, 1e-3), "continuous")
    # The completed time itself and later times are fine.
    assert inst.set_time(1e-3) == OK and inst.set_time(2e-3) == OK


@pytest.mark.parametrize("value", [NAN, INF, -INF, 1e300, -1e300])
def test_non_finite_or_unresolved_time_is_refused(me, value):
    inst = me.continuous_time_mode(steps=3)
    refused(me, inst, "set_time", (value,), unresolved_message(value, time_limit()), "continuous")
    assert inst.euler_step(1e-4) == (OK, 0, 0)


LIMITS = [
    # (the parameters, what SetTime(limit) answers: None = OK, else a part of the refusal)
    ({"variant": 2, "road": 1}, None),  # 0.01 s
    ({"variant": 3, "road": 1}, None),  # the delay 0.0002 s
    ({"variant": 3, "tau": 1e-8, "road": 1}, None),  # folded delay: 0.01 s
    ({"variant": 2, **ROADS[2]}, "road nodes"),  # 1 ms nodes
    ({"variant": 2, "road": 3, "road_sample_interval": 0.002}, "road nodes"),
    ({"variant": 2, "road": 3, "road_sample_interval": 0.5}, "road nodes"),  # 0.01 s
]


@pytest.mark.parametrize("values, at_limit", LIMITS, ids=[
    "-".join(f"{k}={v}" for k, v in values.items()) for values, _ in LIMITS])
def test_the_time_limit_is_2_42_times_the_finest_time_resolved(me, values, at_limit):
    """Just beyond 2^42 times the finest time the model resolves, a time is
    refused naming the limit; at the limit it is taken, or refused for the
    random road's nodes it would need."""
    inst = me.continuous_time_mode(**values)
    limit = time_limit(**values)
    beyond = math.nextafter(limit, INF)
    refused(me, inst, "set_time", (beyond,), unresolved_message(beyond, limit), "continuous")
    if at_limit is None:
        assert inst.set_time(limit) == OK, inst.log.last()
        status, dx = inst.derivatives()
        assert status == OK and all(math.isfinite(v) for v in dx), (dx, inst.log.last())
    else:
        refused_naming(me, inst, "set_time", (limit,), [f"time {rust(limit)} s needs", at_limit,
                                                        f"more than the limit of {MAX_ROAD_NODES} per call"])


def test_a_random_road_needing_too_many_nodes_is_refused_naming_the_limit(me):
    """ISO 8608 at 1e5 s: 1e8 road nodes, refused naming the work; a master
    moving on in smaller steps gets there."""
    inst = me.continuous_time_mode(variant=2, **ROADS[2])
    refused_naming(me, inst, "set_time", (1e5,), ["time 100000 s needs 1e8 road nodes generated", "road nodes",
                                                  f"more than the limit of {MAX_ROAD_NODES} per call",
                                                  "CompletedIntegratorStep"])
    # 4000 s: 4e6 nodes, within the limit.
    assert inst.set_time(4000.0) == OK, inst.log.last()
    assert inst.derivatives()[0] == OK


def test_a_trial_time_can_be_taken_back_until_the_step_is_completed(me):
    """An integrator that rejects a step sets an earlier time again: allowed
    back to the last completed step, not before."""
    inst = me.continuous_time_mode(steps=1)
    assert inst.set_time(5e-4) == OK and inst.derivatives()[0] == OK
    assert inst.set_time(2e-4) == OK and inst.derivatives()[0] == OK
    assert inst.set_time(1e-4) == OK
    refused(me, inst, "set_time", (0.5e-4,), floor_message(0.5e-4, 1e-4), "continuous")


def test_a_master_that_never_completes_may_go_back_one_second(me):
    """Without CompletedIntegratorStep the time may go back 1 s from the
    latest time set; further is refused naming both times and the remedy.
    After a completed step, it may go back to that step, however far."""
    inst = me.continuous_time_mode()
    assert inst.set_time(0.4) == OK and inst.set_time(1.5) == OK
    refused(me, inst, "set_time", (0.45,),
            "time 0.45 s is before 0.5 s, the earliest time kept: a master that does not call "
            "CompletedIntegratorStep may go back at most 1 s from the latest time it set (1.5 s); call "
            "CompletedIntegratorStep at the solver's accepted steps, and go back no further than the last of them",
            "continuous")
    assert inst.set_time(0.5) == OK
    assert inst.completed_integrator_step() == (OK, 0, 0)
    assert inst.set_time(1.7) == OK and inst.set_time(0.5) == OK  # 1.2 s back, to the completed step
    refused(me, inst, "set_time", (0.49,), floor_message(0.49, 0.5), "continuous")


def test_time_before_an_event_is_refused_in_event_mode(me):
    inst = me.continuous_time_mode()
    assert inst.set_time(1e-3) == OK
    assert inst.enter_event_mode() == OK
    assert me.discrete(inst)[:2] == (OK, 0)
    refused(me, inst, "set_time", (5e-4,), floor_message(5e-4, 1e-3), "event")
    assert inst.enter_continuous_time_mode() == OK
    assert inst.set_time(1.5e-3) == OK


def max_rss_kib():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB on Linux


def answered(me, inst, key, args, values=None):
    """`key` called: the Error status with one log line naming the
    function, or OK with nothing logged and every value in `values` finite.
    Returns (status, the message or None)."""
    count = len(inst.log.messages)
    status = me.call(inst, key, *args)
    logged = inst.log.since(count)
    if status == ERROR:
        assert len(logged) == 1 and logged[0][:2] == (ERROR, "logStatusError"), logged
        assert logged[0][2].startswith(f"{me.fn[key]}: "), logged
        return status, logged[0][2]
    assert status == OK and not logged, (status, logged)
    if values is not None:
        assert all(math.isfinite(v) for v in values), list(values)
    return status, None


@pytest.mark.parametrize("variant", [2, 3])
@pytest.mark.parametrize("road", list(ROADS), ids=["input", "harmonic", "iso-C", "paper"])
def test_bad_times_are_refused_or_give_finite_values_in_little_memory(me, road, variant):
    """SetTime to 1e5, 1e9 and 1e308 s, then the states set again, the
    derivatives and the event indicators: each refused (one log line) or
    finite; a time is refused when it is beyond 2^42 times the finest time
    resolved, or needs more random-road nodes than the limit. The process
    grows by less than 100 MB."""
    values = {"variant": variant, **ROADS[road]}
    limit, interval = time_limit(**values), node_interval(**values)
    rss = max_rss_kib()
    inst = me.continuous_time_mode(**values)
    for far in (1e5, 1e9, 1e308):
        before = inst.snapshot()
        status, message = answered(me, inst, "set_time", (far,))
        if far > limit:
            assert message == f"{me.fn['set_time']}: {unresolved_message(far, limit)}", message
        elif interval is not None and far / interval > MAX_ROAD_NODES:
            assert message is not None and "road nodes" in message and str(MAX_ROAD_NODES) in message, message
        else:
            assert status == OK
        if status == ERROR:
            assert inst.snapshot() == before
        status, x = inst.continuous_states()
        assert status == OK and all(math.isfinite(v) for v in x), x
        answered(me, inst, "set_states", (array(c_double, x), NX))
        dx, z = vector(NX), vector(NZ)
        answered(me, inst, "derivatives", (dx, NX), dx)
        answered(me, inst, "indicators", (z, NZ), z)
    assert max_rss_kib() - rss < 100 * 1024, f"grew by {(max_rss_kib() - rss) / 1024:.0f} MB"


# ------------------------------------------------------------ going back

H = 1e-3  # the master's step (s)
GOING_BACK_ROADS = {"harmonic": ROADS[1], "iso-C": ROADS[2]}
SUSPENSIONS = {"tdvass-tau-0.011": {"variant": 3, "tau": 0.011}, "pvass": {"variant": 2}}


def t_of(k):
    """The time of step k, computed alike in every run."""
    return k * H


def euler(inst, k_from, k_to, complete):
    """Explicit Euler steps of H from t_of(k_from) to t_of(k_to) with the
    FMU's derivatives, each completed if `complete`."""
    for k in range(k_from, k_to):
        status, x = inst.continuous_states()
        assert status == OK, inst.log.last()
        status, dx = inst.derivatives()
        assert status == OK, inst.log.last()
        assert inst.set_time(t_of(k + 1)) == OK, inst.log.last()
        assert inst.set_continuous_states([a + H * b for a, b in zip(x, dx)]) == OK, inst.log.last()
        if complete:
            assert inst.completed_integrator_step() == (OK, 0, 0), inst.log.last()


def look_ahead(inst, t0, length, n=10):
    """Trial evaluations (derivatives, event indicators) at t0 + length j/n,
    j = 1..n, with the Euler predictor from t0; returns the states at t0."""
    status, x0 = inst.continuous_states()
    assert status == OK
    status, dx0 = inst.derivatives()
    assert status == OK, inst.log.last()
    for j in range(1, n + 1):
        s = length * j / n
        assert inst.set_time(t0 + s) == OK, inst.log.last()
        assert inst.set_continuous_states([a + s * b for a, b in zip(x0, dx0)]) == OK, inst.log.last()
        assert inst.derivatives()[0] == OK, inst.log.last()
        assert inst.event_indicators()[0] == OK, inst.log.last()
    return x0


def bits(values):
    return [v.hex() for v in values]


def going_back_run(me, values, complete, length=None, at=400, until=600):
    """Euler to t_of(at); if `length`, a look-ahead of `length` s and back
    to t_of(at) with the states of then; Euler on to t_of(until). Returns
    the instance and the bits of the final states, derivatives and event
    indicators."""
    inst = me.continuous_time_mode(**values)
    euler(inst, 0, at, complete)
    if length is not None:
        x0 = look_ahead(inst, t_of(at), length)
        assert inst.set_time(t_of(at)) == OK, inst.log.last()
        assert inst.set_continuous_states(x0) == OK
    euler(inst, at, until, complete)
    out = []
    for read in (inst.continuous_states, inst.derivatives, inst.event_indicators):
        status, v = read()
        assert status == OK, inst.log.last()
        out += bits(v)
    return inst, out


@pytest.mark.parametrize("suspension", list(SUSPENSIONS))
@pytest.mark.parametrize("road", list(GOING_BACK_ROADS))
def test_a_look_ahead_and_back_gives_the_same_bits(me, road, suspension):
    """A master that never completes a step looks ahead 0.15, 0.3 and 1 s
    from 0.4 s and goes back: on to 0.6 s, the same bits as without."""
    values = {**GOING_BACK_ROADS[road], **SUSPENSIONS[suspension]}
    _, plain = going_back_run(me, values, complete=False)
    for length in (0.15, 0.3, 1.0):
        _, back = going_back_run(me, values, complete=False, length=length)
        assert back == plain, length


@pytest.mark.parametrize("suspension", list(SUSPENSIONS))
@pytest.mark.parametrize("road", list(GOING_BACK_ROADS))
def test_a_rejected_trial_step_gives_the_same_bits(me, road, suspension):
    """A master that completes every step tries 0.2 s from 0.4 s, rejects
    it and goes back: the same bits as without; before the last completed
    step stays refused."""
    values = {**GOING_BACK_ROADS[road], **SUSPENSIONS[suspension]}
    _, plain = going_back_run(me, values, complete=True)
    inst, back = going_back_run(me, values, complete=True, length=0.2)
    assert back == plain
    refused(me, inst, "set_time", (0.55,), floor_message(0.55, t_of(600)), "continuous")


@pytest.mark.parametrize("suspension", list(SUSPENSIONS))
@pytest.mark.parametrize("road", list(GOING_BACK_ROADS))
def test_going_back_beyond_the_reach_is_refused_naming_both_times(me, road, suspension):
    """Never completing, a look-ahead of 1.5 s from 0.4 s: 0.4 s is then
    out of reach, refused naming both times and CompletedIntegratorStep;
    the instance stays usable."""
    inst = me.continuous_time_mode(**GOING_BACK_ROADS[road], **SUSPENSIONS[suspension])
    euler(inst, 0, 400, complete=False)
    look_ahead(inst, t_of(400), 1.5)
    refused_naming(me, inst, "set_time", (t_of(400),),
                   ["time 0.4 s is before 0.8", "may go back at most 1 s",
                    f"latest time it set ({rust(t_of(400) + 1.5)} s)", "CompletedIntegratorStep"])
    assert inst.set_time(1.45) == OK, inst.log.last()
    status, dx = inst.derivatives()
    assert status == OK and all(math.isfinite(v) for v in dx), inst.log.last()


# ------------------------------------------------------------ wrong states


def _zeros():
    return (array(c_double, [0.0] * NX), NX)


WRONG_STATE = [
    # (key, arguments, the state it is called in)
    ("derivatives", lambda: (vector(NX), NX), "instantiated"),
    ("derivatives", lambda: (vector(NX), NX), "initialization"),
    ("states", lambda: (vector(NX), NX), "initialization"),
    ("set_time", lambda: (0.0,), "instantiated"),
    ("set_time", lambda: (0.0,), "initialization"),
    ("set_states", _zeros, "event"),
    ("completed", lambda: (1, byref(c_int()), byref(c_int())), "event"),
    ("event", lambda: (), "event"),
    ("continuous", lambda: (), "continuous"),
    ("discrete", None, "continuous"),
    ("set_states", _zeros, "terminated"),
    ("set_time", lambda: (0.0,), "terminated"),
]


def bring_to(me, state):
    if state == "instantiated":
        return me.instance()
    if state == "initialization":
        inst = me.instance()
        me.initialization_mode(inst)
        return inst
    if state == "event":
        return me.event_mode()
    inst = me.continuous_time_mode(steps=2)
    if state == "terminated":
        assert me.call(inst, "terminate") == OK
    return inst


@pytest.mark.parametrize("key, args, state", WRONG_STATE, ids=[f"{k}-in-{s}" for k, _, s in WRONG_STATE])
def test_call_in_the_wrong_state(me, key, args, state):
    inst = bring_to(me, state)
    if key == "discrete":
        arguments = ((byref(fmi2.EventInfo()),) if me.version == "fmi2" else
                     (*[byref(c_uint8()) for _ in range(5)], byref(c_double())))
    elif key == "completed" and me.version == "fmi3":
        arguments = (True, byref(c_bool()), byref(c_bool()))
    else:
        arguments = args()
    refused(me, inst, key, arguments, f"not allowed in state {me.state_name[state]}", state)


@pytest.mark.parametrize("state", ["event", "continuous"])
def test_do_step_on_a_model_exchange_instance(me, state):
    inst = bring_to(me, state)
    before = inst.snapshot()
    assert me.do_step(inst, 0.0, 1e-3) == ERROR
    assert last_error(inst) == f"{me.fn['do_step']}: not allowed in state {me.state_name[state]}"
    assert inst.snapshot() == before


def test_a_parameter_is_tuned_in_event_mode_only(me):
    inst = me.continuous_time_mode(steps=2)
    status, dx = inst.derivatives()
    assert inst.set(g=1000.0) == ERROR
    setter = "fmi2SetReal" if me.version == "fmi2" else "fmi3SetFloat64"
    assert last_error(inst) == (f"{setter}: `g` is a parameter: in Model Exchange it can be changed in Event Mode "
                                "only, not in Continuous-Time Mode (value 1000 refused)")
    assert inst.derivatives() == (OK, dx)
    assert inst.enter_event_mode() == OK
    assert inst.set(g=1000.0) == OK
    assert inst.get("g") == [1000.0]


def test_a_refusal_leaves_the_run_bit_identical(me):
    """A Model Exchange run sprinkled with every kind of refused call gives
    the same states, bit for bit, as a clean run."""
    clean, noisy = me.continuous_time_mode(), me.continuous_time_mode()
    for k in range(30):
        _, x = noisy.continuous_states()
        bad = list(x)
        bad[k % NX] = NAN
        for call in (lambda: noisy.set_continuous_states(bad), lambda: noisy.set_continuous_states(x[:-1]),
                     lambda: noisy.set_time(noisy.time - 1e-4 if k else -1.0), lambda: noisy.set_time(NAN),
                     lambda: me.call(noisy, "derivatives", vector(NX + 1), NX + 1),
                     lambda: me.call(noisy, "indicators", None, NZ), lambda: me.do_step(noisy, noisy.time, 1e-3),
                     lambda: noisy.enter_continuous_time_mode(), lambda: noisy.deserialize(b"garbage")[0]):
            assert call() == ERROR
        for inst in (clean, noisy):
            assert inst.euler_step(1e-4) == (OK, 0, 0)
    assert clean.continuous_states() == noisy.continuous_states()
    assert clean.derivatives() == noisy.derivatives()
    assert clean.event_indicators() == noisy.event_indicators()


# ------------------------------------------------------------- divergence


def test_a_diverging_state_asks_to_terminate(me):
    inst = me.continuous_time_mode(steps=2)
    status, x = inst.continuous_states()
    x[0] = 1e9
    assert inst.set_time(3e-4) == OK
    assert inst.set_continuous_states(x) == OK
    count = len(inst.log.messages)
    status, enter, terminate = inst.completed_integrator_step()
    assert status in (OK, WARNING) and enter == 0 and terminate == 1
    warnings = [m for m in inst.log.since(count) if m[0] == WARNING]
    assert len(warnings) == 1, inst.log.since(count)
    assert warnings[0][1] == "logStatusWarning"
    assert warnings[0][2].startswith(f"{me.fn['completed']}: the state diverged: `x_s` = 1000000000 at t = "
                                     "0.0003 s"), warnings[0]
    # Asked again, not logged again.
    count = len(inst.log.messages)
    assert inst.completed_integrator_step()[2] == 1
    assert not [m for m in inst.log.since(count) if m[0] == WARNING]
    assert inst.enter_event_mode() == OK
    status, terminate, _ = me.discrete(inst)
    assert status == OK and terminate == 1
    assert me.call(inst, "terminate") == OK
    assert inst.machine_state() == me.state_name["terminated"]


def test_a_divergence_seen_first_in_event_mode_is_logged_by_the_event_update(me):
    """Diverged states set and Event Mode entered without a completed step:
    the event update asks to terminate, and its warning names it (the call
    that found the divergence), not fmi2/fmi3CompletedIntegratorStep."""
    inst = me.continuous_time_mode(steps=1)
    status, x = inst.continuous_states()
    x[0] = 1e9
    assert inst.set_continuous_states(x) == OK
    assert inst.enter_event_mode() == OK
    count = len(inst.log.messages)
    status, terminate, _ = me.discrete(inst)
    assert status in (OK, WARNING) and terminate == 1
    warnings = [m for m in inst.log.since(count) if m[0] == WARNING]
    assert len(warnings) == 1, inst.log.since(count)
    assert warnings[0][2].startswith(f"{me.fn['discrete']}: the state diverged: `x_s` = 1000000000"), warnings[0]


def test_a_lift_off_is_logged_by_the_event_update(me):
    """With the unilateral tire, the wheel lifted off the road makes the
    event indicator negative; the event update logs the lift-off under
    logEvents, naming the function called."""
    inst = me.instance(logging_on=True)
    assert inst.initialize_model_exchange(stop=15.0, tire_contact=1) == OK
    assert me.discrete(inst)[:2] == (OK, 0)
    assert inst.enter_continuous_time_mode() == OK
    status, x = inst.continuous_states()
    x[4] = 0.05  # x_t: the wheel 5 cm up
    assert inst.set_time(1e-3) == OK and inst.set_continuous_states(x) == OK
    status, z = inst.event_indicators()
    assert status == OK and z[0] < 0
    assert inst.completed_integrator_step() == (OK, 0, 0)
    assert inst.enter_event_mode() == OK
    count = len(inst.log.messages)
    assert me.discrete(inst)[:2] == (OK, 0)
    events = [m for m in inst.log.since(count) if m[1] == "logEvents"]
    assert len(events) == 1, inst.log.since(count)
    assert events[0][2].startswith(f"{me.fn['discrete']}: lift-off at t = 0.001 s (TDD = "), events[0]


# ------------------------------------------------------------- FMU states


def test_fmu_state_round_trip_in_continuous_time_mode(me):
    inst = me.continuous_time_mode(steps=5)
    status, state = inst.get_state()
    assert status == OK
    saved, then = inst.continuous_states(), inst.time
    for _ in range(5):
        assert inst.euler_step(1e-4) == (OK, 0, 0)
    after = inst.continuous_states()
    # Restored: the states of then, and the time of then (1e-4 s past it is
    # not before the restored completed step).
    setter = inst.lib.fmi2SetFMUstate if me.version == "fmi2" else inst.lib.fmi3SetFMUState
    assert setter(inst.c, state) == OK
    assert inst.continuous_states() == saved
    inst.time = then
    for _ in range(5):
        assert inst.euler_step(1e-4) == (OK, 0, 0)
    assert inst.continuous_states() == after
    # Through bytes, into a fresh Model Exchange instance: the same run.
    data = inst.serialize(state)
    other = me.instance()
    status, moved = other.deserialize(data)
    assert status == OK, other.log.last()
    other_setter = other.lib.fmi2SetFMUstate if me.version == "fmi2" else other.lib.fmi3SetFMUState
    assert other_setter(other.c, moved) == OK
    assert other.machine_state() == me.state_name["continuous"]
    other.time = then
    for _ in range(5):
        assert other.euler_step(1e-4) == (OK, 0, 0)
    assert other.continuous_states() == after


def test_restoring_an_event_mode_state_goes_back_to_event_mode(me):
    inst = me.event_mode()
    status, state = inst.get_state()
    assert status == OK
    assert me.discrete(inst)[0] == OK and inst.enter_continuous_time_mode() == OK
    assert inst.euler_step(1e-4) == (OK, 0, 0)
    setter = inst.lib.fmi2SetFMUstate if me.version == "fmi2" else inst.lib.fmi3SetFMUState
    assert setter(inst.c, state) == OK
    assert inst.machine_state() == me.state_name["event"]
    # Back at t = 0: the completed step at 1e-4 s is undone.
    assert inst.set_time(0.0) == OK


@pytest.mark.parametrize("from_state", ["event", "continuous"])
def test_a_model_exchange_state_is_refused_by_a_co_simulation_instance(me, from_state):
    inst = bring_to(me, from_state)
    data = inst.snapshot()
    cs = me.make() if me.version == "fmi3" else me.make(fmu_type=fmi2.CO_SIMULATION)
    status, handle = cs.deserialize(data)
    assert status == ERROR and not handle.value
    assert last_error(cs) == (f"{me.fn['deserialize']}: a Model Exchange state cannot be restored into a "
                              "Co-Simulation instance")


# ------------------------------------------------------------ no panic


def test_no_call_sequence_of_this_file_made_an_instance_fatal(me):
    """The Model Exchange functions with every bad argument at once, in
    every state: refused or done, never fmi2Fatal/fmi3Fatal."""
    for state in ["instantiated", "initialization", "event", "continuous", "terminated"]:
        inst = bring_to(me, state)
        for key in ["set_states", "derivatives", "indicators", "states", "nominals"]:
            for n in (0, 1, NX - 1, NX, NX + 1):
                for values in (None, vector(NX + 1, NAN), vector(NX + 1, 1e308)):
                    assert me.call(inst, key, values, n) in (OK, ERROR), inst.log.last()
        for t in (NAN, -INF, INF, -1.0, 0.0, 1e300):
            assert me.call(inst, "set_time", t) in (OK, ERROR), inst.log.last()
        assert not [m for m in inst.log.messages if m[0] == FATAL], inst.log.messages


# ------------------------------------------------- the corner and the chassis

CORNER_STATES = ["x_h", "v_h", "x_t", "v_t", "integral_suspension_deflection_squared",
                 "integral_tire_deflection_squared", "contact_loss_time"]
CHASSIS_STATES = ["heave", "pitch", "roll", "heave_velocity", "pitch_rate", "roll_rate",
                  *[f"seat_wk_filter_{k}" for k in range(1, 9)],
                  *[f"integral_{n}_acceleration_squared" for n in ("heave", "pitch", "roll")],
                  "integral_weighted_seat_acceleration_squared", "integral_weighted_seat_acceleration_fourth"]
# (the FMU of FMI 2.0 and of FMI 3.0, the continuous states, the event indicators)
COMPONENTS = {"corner": ((fmi2.corner_fmu_file, fmi3.corner_fmu_file), 7, 1),
              "chassis": ((fmi2.chassis_fmu_file, fmi3.chassis_fmu_file), 19, 0)}
FORCES = ["force_fl", "force_fr", "force_rl", "force_rr"]


def fmu_of(me, model):
    """The FMU of `model` for the version of `me`."""
    return COMPONENTS[model][0][me.version == "fmi3"]()


def component(me, model, **values):
    """A Model Exchange instance of the corner or the chassis in
    Continuous-Time Mode at t = 0."""
    inst = me.instance(fmu=fmu_of(me, model))
    assert inst.initialize_model_exchange(stop=15.0, **values) == OK, inst.log.last()
    assert me.discrete(inst)[0] == OK
    assert inst.enter_continuous_time_mode() == OK
    return inst


def component_step(inst, model, h=1e-4):
    """One explicit Euler step of h of the component, completed, its inputs
    (the body attachment or the forces) set first from the time."""
    n = COMPONENTS[model][1]
    t = inst.time
    if model == "corner":
        assert inst.set(body_displacement=2e-3 * math.sin(11 * t), body_velocity=2.2e-2 * math.cos(11 * t)) == OK
    else:
        assert inst.set(**{f: 400.0 * math.sin(9 * t + i) for i, f in enumerate(FORCES)}) == OK
    status, x = inst.continuous_states(n)
    assert status == OK, inst.log.last()
    status, dx = inst.derivatives(n)
    assert status == OK, inst.log.last()
    assert inst.set_time(t + h) == OK, inst.log.last()
    inst.time = t + h
    assert inst.set_continuous_states([a + h * b for a, b in zip(x, dx)]) == OK, inst.log.last()
    assert inst.completed_integrator_step()[0] == OK, inst.log.last()


def component_names(model):
    return CORNER_STATES if model == "corner" else CHASSIS_STATES


@pytest.mark.parametrize("model", list(COMPONENTS))
def test_a_component_s_state_names_are_those_of_its_description(me, model):
    inst = me.instance(fmu=fmu_of(me, model))
    for name in component_names(model):
        assert name in inst.vr, name


@pytest.mark.parametrize("value", [NAN, INF, -INF])
@pytest.mark.parametrize("model", list(COMPONENTS))
def test_a_component_s_non_finite_states_are_refused_naming_them(me, model, value):
    inst = component(me, model)
    for _ in range(5):
        component_step(inst, model)
    n = COMPONENTS[model][1]
    status, x = inst.continuous_states(n)
    for i, name in enumerate(component_names(model)):
        bad = list(x)
        bad[i] = value
        refused(me, inst, "set_states", (array(c_double, bad), n),
                f"continuous state {i} (`{name}`) = {rust(value)} is not finite", "continuous")
    refused(me, inst, "set_states", (array(c_double, x[:-1]), n - 1),
            f"{n - 1} continuous states given, the model has {n}", "continuous")
    assert inst.continuous_states(n) == (OK, x)
    component_step(inst, model)  # still usable


@pytest.mark.parametrize("value", [NAN, INF, -INF])
def test_the_corner_s_non_finite_or_going_back_times_are_refused(me, value):
    inst = component(me, "corner")
    for _ in range(5):
        component_step(inst, "corner")
    refused_naming(me, inst, "set_time", (value,), [f"time {rust(value)} s is not finite or beyond"])
    # Before the last completed step: refused naming both times.
    refused(me, inst, "set_time", (3e-4,), floor_message(3e-4, inst.time), "continuous")
    component_step(inst, "corner")


@pytest.mark.parametrize("value", [NAN, INF, -INF, -1.0])
def test_the_chassis_s_non_finite_or_early_times_are_refused(me, value):
    inst = component(me, "chassis")
    for _ in range(5):
        component_step(inst, "chassis")
    refused(me, inst, "set_time", (value,),
            f"invalid time {rust(value)} s for `time`: must be finite and not before the start time", "continuous")
    component_step(inst, "chassis")


def refused_value(me, inst, state, **values):
    """Setting `values` is refused: the Error status, one log line naming
    the variable and its value, nothing changed."""
    ((name, value),) = values.items()
    before = inst.snapshot()
    count = len(inst.log.messages)
    assert inst.set(**values) == ERROR
    logged = inst.log.since(count)
    assert len(logged) == 1 and logged[0][:2] == (ERROR, "logStatusError"), logged
    setter = "fmi2SetReal" if me.version == "fmi2" else "fmi3SetFloat64"
    message = logged[0][2]
    assert message.startswith(f"{setter}: ") and f"`{name}`" in message and rust(value) in message, message
    assert inst.machine_state() == me.state_name[state]
    assert inst.snapshot() == before
    return message


CORNER_INPUTS = [("body_displacement", NAN), ("body_displacement", -INF), ("body_displacement", 1e9),
                 ("body_velocity", INF), ("body_velocity", NAN), ("x_g", NAN), ("x_g", INF)]


@pytest.mark.parametrize("name, value", CORNER_INPUTS)
@pytest.mark.parametrize("state", ["event", "continuous"])
def test_the_corner_s_bad_inputs_are_refused_naming_them(me, name, value, state):
    inst = component(me, "corner")
    for _ in range(3):
        component_step(inst, "corner")
    if state == "event":
        assert inst.enter_event_mode() == OK
    refused_value(me, inst, state, **{name: value})
    if state == "event":
        assert me.discrete(inst)[0] == OK and inst.enter_continuous_time_mode() == OK
    component_step(inst, "corner")


@pytest.mark.parametrize("name", FORCES)
@pytest.mark.parametrize("value", [NAN, INF, -INF])
def test_the_chassis_s_non_finite_forces_are_refused_naming_them(me, name, value):
    inst = component(me, "chassis")
    for _ in range(3):
        component_step(inst, "chassis")
    refused_value(me, inst, "continuous", **{name: value})
    component_step(inst, "chassis")


def test_forces_too_large_for_the_chassis_make_its_derivatives_refused(me):
    """Finite forces whose squared accelerations overflow: the derivatives
    are refused naming the first that is not finite; smaller forces go on."""
    inst = component(me, "chassis")
    component_step(inst, "chassis")
    assert inst.set(force_fl=1e300) == OK
    refused_naming(me, inst, "derivatives", (vector(19), 19),
                   ["the derivative of `integral_heave_acceleration_squared` is inf at t = 0.0001 s",
                    "too large for the chassis"])
    component_step(inst, "chassis")
    status, dx = inst.derivatives(19)
    assert status == OK and all(math.isfinite(v) for v in dx)


@pytest.mark.parametrize("name, value", [("mass", 0.0), ("mass", -1380.0), ("mass", NAN), ("pitch_inertia", 0.0),
                                         ("pitch_inertia", INF), ("roll_inertia", -400.0), ("roll_inertia", 0.0)])
@pytest.mark.parametrize("state", ["instantiated", "initialization"])
def test_the_chassis_refuses_a_non_positive_mass_or_inertia(me, name, value, state):
    inst = me.instance(fmu=fmu_of(me, "chassis"))
    if state == "initialization":
        me.initialization_mode(inst)
    refused_value(me, inst, state, **{name: value})
    # The start values stay: the model starts and runs.
    if state == "instantiated":
        me.initialization_mode(inst)
    assert inst.exit() == OK, inst.log.last()
    assert me.discrete(inst)[0] == OK and inst.enter_continuous_time_mode() == OK
    component_step(inst, "chassis")




def test_the_chassis_s_fixed_parameters_are_refused_once_it_runs(me):
    inst = component(me, "chassis")
    setter = "fmi2SetReal" if me.version == "fmi2" else "fmi3SetFloat64"
    before = inst.snapshot()
    assert inst.set(mass=1000.0) == ERROR
    message = last_error(inst)
    assert message.startswith(f"{setter}: ") and "`mass`" in message, message
    assert inst.snapshot() == before


@pytest.mark.parametrize("model", list(COMPONENTS))
def test_a_component_s_model_exchange_state_restores_the_run_to_the_bit(me, model):
    """Saved mid-run, set back, and through bytes into a fresh instance: the
    same states, derivatives and outputs, bit for bit."""
    n = COMPONENTS[model][1]
    inst = component(me, model)
    for _ in range(50):
        component_step(inst, model)
    status, state = inst.get_state()
    assert status == OK
    data = inst.serialize(state)
    then = inst.time

    def run(target):
        target.time = then
        for _ in range(50):
            component_step(target, model)
        out = target.continuous_states(n)[1] + target.derivatives(n)[1]
        names = ["body_force", "rms_suspension_deflection"] if model == "corner" else [
            "seat_acceleration", "rms_weighted_seat_acceleration", "seat_vibration_dose_value"]
        return bits(out + target.get(*names))

    first = run(inst)
    setter = inst.lib.fmi2SetFMUstate if me.version == "fmi2" else inst.lib.fmi3SetFMUState
    assert setter(inst.c, state) == OK
    assert run(inst) == first
    other = me.instance(fmu=fmu_of(me, model))
    status, moved = other.deserialize(data)
    assert status == OK, other.log.last()
    other_setter = other.lib.fmi2SetFMUstate if me.version == "fmi2" else other.lib.fmi3SetFMUState
    assert other_setter(other.c, moved) == OK
    assert other.machine_state() == me.state_name["continuous"]
    assert run(other) == first


@pytest.mark.parametrize("model", list(COMPONENTS))
def test_no_bad_call_made_a_component_fatal(me, model):
    """The Model Exchange functions of the corner and the chassis with
    every bad argument, in every state: refused or done, never Fatal."""
    n, nz = COMPONENTS[model][1], COMPONENTS[model][2]
    for state in ["instantiated", "initialization", "event", "continuous", "terminated"]:
        inst = me.instance(fmu=fmu_of(me, model))
        if state != "instantiated":
            me.initialization_mode(inst)
        if state in ("event", "continuous", "terminated"):
            assert inst.exit() == OK
        if state in ("continuous", "terminated"):
            assert me.discrete(inst)[0] == OK and inst.enter_continuous_time_mode() == OK
            component_step(inst, model)
        if state == "terminated":
            assert me.call(inst, "terminate") == OK
        for key in ["set_states", "derivatives", "indicators", "states", "nominals"]:
            for k in (0, 1, n - 1, n, n + 1, nz, NX):
                for values in (None, vector(NX + 1, NAN), vector(NX + 1, 1e308)):
                    assert me.call(inst, key, values, k) in (OK, ERROR), inst.log.last()
        for t in (NAN, -INF, INF, -1.0, 0.0, 1e300):
            assert me.call(inst, "set_time", t) in (OK, ERROR), inst.log.last()
        names = ["body_displacement", "body_velocity", "x_g"] if model == "corner" else [*FORCES, "mass"]
        for name in names:
            for value in (NAN, INF, -INF, 1e308, 0.0):
                assert inst.set(**{name: value}) in (OK, ERROR), inst.log.last()
        assert not [m for m in inst.log.messages if m[0] == FATAL], inst.log.messages
