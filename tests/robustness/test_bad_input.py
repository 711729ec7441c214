"""Bad input to the real shared library: every case asserts the exact
status, the log message where there is an instance to log through, that a
refused call changed nothing, and (fixture teardown) that the process and
the library are still alive. One file for the FMI 2.0 surface on purpose
(the fixtures load the library once): hence its length."""

import ctypes
import math
from ctypes import byref, c_char, c_double, c_int, c_size_t, c_uint, c_void_p

import pytest
from conftest import rust

import fmi2
from fmi2 import DISCARD, ERROR, OK, WARNING, array

NAN, INF = float("nan"), float("inf")


def last_error(inst):
    status, category, message = inst.log.last()
    assert status == ERROR and category == "logStatusError", inst.log.last()
    return message


# ------------------------------------------------------------ NULL instance

_vr = array(c_uint, [31])
_out = (c_double * 4)()
_int = (c_int * 4)()
_buf = (c_char * 64)()
_size = c_size_t()
_slot = c_void_p()

NULL_INSTANCE_CALLS = {
    "fmi2SetDebugLogging": (1, 0, None),
    "fmi2SetupExperiment": (0, 0.0, 0.0, 0, 0.0),
    "fmi2EnterInitializationMode": (),
    "fmi2ExitInitializationMode": (),
    "fmi2Terminate": (),
    "fmi2Reset": (),
    "fmi2GetReal": (_vr, 1, _out),
    "fmi2GetInteger": (_vr, 1, _int),
    "fmi2GetBoolean": (_vr, 1, _int),
    "fmi2GetString": (_vr, 1, _buf),
    "fmi2SetReal": (_vr, 1, _out),
    "fmi2SetInteger": (_vr, 1, _int),
    "fmi2SetBoolean": (_vr, 1, _int),
    "fmi2SetString": (_vr, 1, _buf),
    "fmi2GetFMUstate": (byref(_slot),),
    "fmi2SetFMUstate": (None,),
    "fmi2FreeFMUstate": (byref(_slot),),
    "fmi2SerializedFMUstateSize": (None, byref(_size)),
    "fmi2SerializeFMUstate": (None, _buf, 64),
    "fmi2DeSerializeFMUstate": (_buf, 64, byref(_slot)),
    "fmi2GetDirectionalDerivative": (_vr, 1, _vr, 1, _out, _out),
    "fmi2SetRealInputDerivatives": (_vr, 1, _int, _out),
    "fmi2GetRealOutputDerivatives": (_vr, 1, _int, _out),
    "fmi2DoStep": (0.0, 0.001, 1),
    "fmi2CancelStep": (),
    "fmi2GetStatus": (0, _int),
    "fmi2GetRealStatus": (2, _out),
    "fmi2GetIntegerStatus": (0, _int),
    "fmi2GetBooleanStatus": (3, _int),
    "fmi2GetStringStatus": (0, _buf),
    "fmi2EnterEventMode": (),
    "fmi2NewDiscreteStates": (None,),
    "fmi2EnterContinuousTimeMode": (),
    "fmi2CompletedIntegratorStep": (1, None, None),
    "fmi2SetTime": (0.0,),
    "fmi2SetContinuousStates": (None, 0),
    "fmi2GetDerivatives": (None, 0),
    "fmi2GetEventIndicators": (None, 0),
    "fmi2GetContinuousStates": (None, 0),
    "fmi2GetNominalsOfContinuousStates": (None, 0),
}


@pytest.mark.parametrize("function", sorted(NULL_INSTANCE_CALLS))
def test_null_instance_is_refused(lib, function):
    assert getattr(lib, function)(None, *NULL_INSTANCE_CALLS[function]) == ERROR


@pytest.mark.parametrize("function", ["fmi2Terminate", "fmi2DoStep", "fmi2GetReal", "fmi2FreeFMUstate"])
def test_foreign_pointer_as_instance_is_refused(lib, function):
    """A pointer to memory that is not a component (zeros) is recognised."""
    fake = (ctypes.c_uint64 * 16)()
    assert getattr(lib, function)(ctypes.addressof(fake), *NULL_INSTANCE_CALLS[function]) == ERROR
    lib.fmi2FreeInstance(ctypes.addressof(fake))  # ignored, no crash
    assert list(fake) == [0] * 16


def test_free_instance_null(lib):
    lib.fmi2FreeInstance(None)
    assert lib.fmi2GetVersion() == b"2.0"


# --------------------------------------------------------------- instantiate


def refused_instantiation(lib, expected, **kwargs):
    log = fmi2.Log()
    inst = fmi2.Instance(lib, log=log, **kwargs)
    assert not inst.ok
    assert len(log.messages) == 1
    status, category, message = log.messages[0]
    assert status == ERROR and category == "logStatusError"
    assert message.startswith("fmi2Instantiate: ") and expected in message, message


def test_wrong_guid(lib):
    refused_instantiation(lib, "GUID {00000000-0000-0000-0000-000000000000} does not match",
                          guid_=b"{00000000-0000-0000-0000-000000000000}")


def test_null_guid(lib):
    refused_instantiation(lib, "fmuGUID is NULL", guid_=None)


def test_model_exchange_type_is_accepted(make):
    """fmi2ModelExchange makes an instance (since Model Exchange was added),
    without an error logged."""
    inst = make(fmu_type=fmi2.MODEL_EXCHANGE)
    assert inst.ok
    assert not [m for m in inst.log.messages if m[0] != OK], inst.log.messages
    assert inst.machine_state() == "instantiated"


def test_unknown_fmu_type(lib):
    refused_instantiation(lib, "unknown fmuType 7", fmu_type=7)


def test_empty_instance_name(lib):
    refused_instantiation(lib, "instanceName is empty", name=b"")


def test_null_instance_name(lib):
    refused_instantiation(lib, "instanceName is NULL", name=None)


@pytest.mark.parametrize(
    "uri, reason",
    [
        (b"http://example.com/resources", "unsupported scheme `http`"),
        (b"file://server/share/resources", "unsupported host `server`"),
        (b"relative/path", "no scheme"),
        (b"file:relative/path", "not an absolute file URI"),
        (b"file:///tmp/%zz", "invalid percent-escape"),
        (b"file:///tmp/%4", "invalid percent-escape"),
        (b"file:///tmp/%00x", "NUL byte"),
        (b"file:///tmp/a?b", "query or fragment"),
        (b"file://", "no path after the authority"),
    ],
)
def test_malformed_resource_uri(lib, uri, reason):
    refused_instantiation(lib, f"fmuResourceLocation `{uri.decode()}` is not a valid file URI: ", resources=uri)
    refused_instantiation(lib, reason, resources=uri)


@pytest.mark.parametrize("uri", [None, b"", b"file:///tmp/r%20x/resources", b"FILE://localhost/tmp/r"])
def test_accepted_resource_uris(make, uri):
    assert make(resources=uri).ok


def test_null_callbacks_and_null_logger(lib):
    g = fmi2.guid().encode()
    assert not lib.fmi2Instantiate(b"a", 1, g, None, None, 0, 0)
    callbacks = fmi2.CallbackFunctions()  # logger NULL
    assert not lib.fmi2Instantiate(b"a", 1, g, None, byref(callbacks), 0, 0)


_nx = (c_double * fmi2.NX)()
_ni = (c_double * fmi2.NZ)()
_event_info = fmi2.EventInfo()
# Each Model Exchange function with valid arguments but the instance.
MODEL_EXCHANGE_CALLS = {
    "fmi2EnterEventMode": (),
    "fmi2NewDiscreteStates": (byref(_event_info),),
    "fmi2EnterContinuousTimeMode": (),
    "fmi2CompletedIntegratorStep": (1, byref(c_int()), byref(c_int())),
    "fmi2SetTime": (0.0,),
    "fmi2SetContinuousStates": (_nx, fmi2.NX),
    "fmi2GetDerivatives": (_nx, fmi2.NX),
    "fmi2GetEventIndicators": (_ni, fmi2.NZ),
    "fmi2GetContinuousStates": (_nx, fmi2.NX),
    "fmi2GetNominalsOfContinuousStates": (_nx, fmi2.NX),
}


@pytest.mark.parametrize("state", ["instantiated", "stepComplete"])
def test_model_exchange_functions_on_a_cs_instance(make, state):
    """The state table refuses every Model Exchange function in the states
    of a Co-Simulation instance, naming the state; nothing changes."""
    inst = make()
    if state == "stepComplete":
        inst.initialize(stop=15.0)
    for function, args in MODEL_EXCHANGE_CALLS.items():
        assert getattr(inst.lib, function)(inst.c, *args) == ERROR
        assert last_error(inst) == f"{function}: not allowed in state {state}"
        assert inst.machine_state() == state
    if state == "stepComplete":
        assert inst.step(0.01) == OK


# ---------------------------------------------------------- arrays and NULL


@pytest.fixture
def init_mode(make):
    inst = make()
    assert inst.setup(0.0, 15.0) == OK and inst.enter() == OK
    return inst


@pytest.mark.parametrize("function", ["fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean", "fmi2SetReal",
                                      "fmi2SetInteger", "fmi2SetBoolean", "fmi2GetString", "fmi2SetString"])
def test_null_value_reference_array_with_nvr(init_mode, function):
    assert getattr(init_mode.lib, function)(init_mode.c, None, 2, _out) == ERROR
    assert last_error(init_mode) == f"{function}: vr is NULL while its length is 2"


@pytest.mark.parametrize("function", ["fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean", "fmi2SetReal",
                                      "fmi2SetInteger", "fmi2SetBoolean", "fmi2GetString", "fmi2SetString"])
def test_null_value_array_with_nvr(init_mode, function):
    vr = array(c_uint, [init_mode.vr["g"]])
    assert getattr(init_mode.lib, function)(init_mode.c, vr, 1, None) == ERROR
    assert last_error(init_mode) == f"{function}: value is NULL while its length is 1"


@pytest.mark.parametrize("function", ["fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean", "fmi2SetReal",
                                      "fmi2SetInteger", "fmi2SetBoolean", "fmi2GetString", "fmi2SetString"])
def test_nvr_zero_with_null_arrays_is_ok(init_mode, function):
    assert getattr(init_mode.lib, function)(init_mode.c, None, 0, None) == OK


def test_null_arrays_of_derivative_functions(initialized):
    inst = initialized()
    lib = inst.lib
    vr = array(c_uint, [inst.vr["x_s"]])
    assert lib.fmi2GetDirectionalDerivative(inst.c, vr, 1, vr, 1, None, _out) == ERROR
    assert last_error(inst) == "fmi2GetDirectionalDerivative: dvKnown is NULL while its length is 1"
    assert lib.fmi2GetRealOutputDerivatives(inst.c, vr, 1, None, _out) == ERROR
    assert last_error(inst) == "fmi2GetRealOutputDerivatives: order is NULL while its length is 1"
    assert lib.fmi2SetRealInputDerivatives(inst.c, None, 1, _int, _out) == ERROR
    assert last_error(inst) == "fmi2SetRealInputDerivatives: vr is NULL while its length is 1"


def test_null_strings_of_set_debug_logging(make):
    inst = make()
    assert inst.lib.fmi2SetDebugLogging(inst.c, 1, 2, None) == ERROR
    assert last_error(inst) == "fmi2SetDebugLogging: categories is NULL while its length is 2"
    categories = (ctypes.c_char_p * 2)(b"logEvents", None)
    assert inst.lib.fmi2SetDebugLogging(inst.c, 1, 2, categories) == ERROR
    assert last_error(inst) == "fmi2SetDebugLogging: categories[1] is NULL"
    categories = (ctypes.c_char_p * 1)(b"logEverything")
    assert inst.lib.fmi2SetDebugLogging(inst.c, 1, 1, categories) == ERROR
    assert "unknown log category `logEverything`" in last_error(inst)


def test_null_status_pointers(initialized):
    inst = initialized()
    for function in ["fmi2GetStatus", "fmi2GetRealStatus", "fmi2GetIntegerStatus", "fmi2GetBooleanStatus",
                     "fmi2GetStringStatus"]:
        assert getattr(inst.lib, function)(inst.c, 2, None) == ERROR
        assert last_error(inst) == f"{function}: value is NULL while its length is 1"


def test_status_kinds(initialized):
    inst = initialized()
    assert inst.real_status(fmi2.DO_STEP_STATUS)[0] == DISCARD
    assert inst.real_status(99)[0] == ERROR
    assert last_error(inst) == "fmi2GetRealStatus: unknown status kind 99"
    status = c_int()
    assert inst.lib.fmi2GetStatus(inst.c, fmi2.PENDING_STATUS, byref(status)) == DISCARD
    assert inst.real_status() == (OK, 0.0)
    assert inst.boolean_status() == (OK, 0)


# ------------------------------------------------------ value references


@pytest.mark.parametrize("vr", [0, 49, 9999, 2**31, 2**32 - 1])
def test_unknown_value_reference(init_mode, vr):
    status, _ = init_mode.get_real([vr])
    assert status == ERROR
    assert last_error(init_mode) == f"fmi2GetReal: unknown value reference {vr} (for a Real)"
    assert init_mode.set_real([vr], [1.0]) == ERROR
    assert init_mode.set_integer([vr], [1]) == ERROR
    assert last_error(init_mode) == f"fmi2SetInteger: unknown value reference {vr} (for a Integer)"


def test_wrong_type_for_value_reference(init_mode):
    out = array(c_int, [0])
    assert init_mode.lib.fmi2GetInteger(init_mode.c, array(c_uint, [init_mode.vr["g"]]), 1, out) == ERROR
    assert last_error(init_mode) == "fmi2GetInteger: value reference 10 is `g`, a Real, not a Integer"
    assert init_mode.set_real([init_mode.vr["variant"]], [1.0]) == ERROR
    assert "`variant`, a Integer, not a Real" in last_error(init_mode)


def test_no_string_variables(init_mode):
    out = (ctypes.c_char_p * 1)()
    assert init_mode.lib.fmi2GetString(init_mode.c, array(c_uint, [1]), 1, out) == ERROR
    assert "not a String" in last_error(init_mode)


def test_one_bad_reference_refuses_the_whole_call(init_mode):
    assert init_mode.set_real([init_mode.vr["g"], 9999], [1000.0, 1.0]) == ERROR
    assert init_mode.get("g") == [5386.0]


# --------------------------------------------------- causality, variability


def test_setting_an_output(initialized):
    inst = initialized()
    assert inst.set_real([inst.vr["x_s"]], [1.0]) == ERROR
    assert last_error(inst) == "fmi2SetReal: `x_s` is an output and cannot be set (value 1 refused)"


def test_setting_a_calculated_parameter(initialized):
    inst = initialized()
    assert inst.set_real([inst.vr["spectral_abscissa"]], [-1.0]) == ERROR
    assert "`spectral_abscissa` is a calculated parameter" in last_error(inst)
    assert inst.set_boolean([inst.vr["stable"]], [1]) == ERROR
    assert "`stable` is a calculated parameter" in last_error(inst)


@pytest.mark.parametrize("name, value", [("m_s", 300.0), ("tau", 0.01), ("variant", 1), ("road_seed", 5),
                                         ("x_s_start", 0.1)])
def test_setting_a_fixed_parameter_after_initialization(initialized, name, value):
    inst = initialized()
    before = inst.get("m_s", "tau")
    status = inst.set(**{name: value})
    assert status == ERROR
    assert f"`{name}` is a fixed parameter and cannot be changed after initialization" in last_error(inst)
    assert inst.get("m_s", "tau") == before
    assert inst.machine_state() == "stepComplete"


@pytest.mark.parametrize("name, value", [("g", 1000.0), ("w_ba", 1.0), ("w_sdd", 0.0), ("w_tdd", 2.5)])
def test_tunable_parameter_in_step_complete(initialized, name, value):
    inst = initialized()
    assert inst.step(0.1) == OK
    assert inst.set(**{name: value}) == OK
    assert inst.get(name) == [value]
    assert inst.step(0.1) == OK


def test_input_in_step_complete(initialized):
    inst = initialized(road=0)
    assert inst.set(x_g=0.01) == OK
    assert inst.step(0.1) == OK
    assert inst.get("road_displacement") == [0.01]


# ----------------------------------------------------- values out of range

BAD_VALUES = [
    ("m_s", -345.0, "must be > 0"),
    ("m_h", 0.0, "must be > 0"),
    ("m_t", -INF, "must be finite"),
    ("m_s", NAN, "must be finite"),
    ("k_s", -1.0, "must be >= 0"),
    ("k_t", INF, "must be finite"),
    ("c_h", NAN, "must be finite"),
    ("g", NAN, "must be finite"),
    ("g", -INF, "must be finite"),
    ("tau", -2e-4, "must be >= 0"),
    ("tau", NAN, "must be finite"),
    ("max_internal_step", -1e-4, "must be >= 0"),
    ("vehicle_speed", 0.0, "must be > 0"),
    ("road_cutoff_frequency", -0.1, "must be > 0"),
    ("road_sample_interval", 0.0, "must be > 0"),
    ("road_amplitude", INF, "must be finite"),
    ("road_amplitude", 1e4, "exceeds 1e3"),
    ("road_angular_frequency", 1e7, "exceeds 1e6"),
    ("w_ba", -0.1, "must be >= 0"),
    ("w_tdd", 1e300, "exceeds 1e12"),
    ("x_s_start", INF, "must be finite"),
    ("x_t_start", -2e3, "exceeds 1e3"),
    ("v_s_start", 1e7, "exceeds 1e6"),
    ("x_g", NAN, "must be finite"),
    ("x_g", 1e6, "exceeds 1e3"),
    ("road_class", 9, "must be in 1..=8"),
    ("road_class", 0, "must be in 1..=8"),
    ("road", 4, "must be in 0..=3"),
    ("variant", 0, "must be in 1..=3"),
    ("road_seed", -1, "must be in 0..=2147483647"),
]


@pytest.mark.parametrize("name, value, reason", BAD_VALUES, ids=[f"{n}={v}" for n, v, _ in BAD_VALUES])
def test_bad_value_is_refused_naming_variable_and_value(init_mode, name, value, reason):
    before = init_mode.get("m_s", "g", "tau", "road_amplitude")
    status = init_mode.set(**{name: value})
    assert status == ERROR
    message = last_error(init_mode)
    function = "fmi2SetInteger" if isinstance(value, int) else "fmi2SetReal"
    assert message.startswith(f"{function}: invalid value {rust(value)} for `{name}`: "), message
    assert reason in message, message
    assert init_mode.get("m_s", "g", "tau", "road_amplitude") == before
    assert init_mode.machine_state() == "initializationMode"
    assert init_mode.exit() == OK  # nothing was applied


# Admissible alone, refused when the simulation is built (the instance stays
# in initialization mode and can be corrected).
BAD_AT_INITIALIZATION = [
    ("tau", 1e300, "the delay needs more than 8388608 history nodes"),
    ("tau", 1e4, "the delay needs more than 8388608 history nodes"),
    ("k_s", 1e300, "exceeds the numerical limit"),
    ("m_h", 1e-300, "exceeds the numerical limit"),
    ("g", -1e14, "exceeds the numerical limit"),
]


@pytest.mark.parametrize("name, value, reason", BAD_AT_INITIALIZATION,
                         ids=[f"{n}={v}" for n, v, _ in BAD_AT_INITIALIZATION])
def test_bad_combination_is_refused_at_initialization(init_mode, name, value, reason):
    assert init_mode.set(**{name: value}) == OK
    assert init_mode.exit() == ERROR
    message = last_error(init_mode)
    assert message.startswith("fmi2ExitInitializationMode: invalid "), message
    assert f"`{name}`" in message and rust(value) in message and reason in message, message
    assert init_mode.machine_state() == "initializationMode"
    # While the combination stands, outputs are refused, not made up.
    assert init_mode.get_real([init_mode.vr["body_acceleration"]])[0] == ERROR
    assert init_mode.set(**{name: {"tau": 2e-4, "k_s": 16000.0, "m_h": 4.05, "g": 5386.0}[name]}) == OK
    assert init_mode.exit() == OK


# The corner's FMU (tdvass-corner.fmu, the same library under the corner's
# GUID): its own parameters and body inputs.
CORNER_BAD_VALUES = [
    ("body_displacement", NAN, "must be finite"),
    ("body_displacement", INF, "must be finite"),
    ("body_displacement", -INF, "must be finite"),
    ("body_displacement", 1e6, "exceeds 1e3"),
    ("body_velocity", NAN, "must be finite"),
    ("body_velocity", -INF, "must be finite"),
    ("body_velocity", 1e7, "exceeds 1e6"),
    ("static_load", 0.0, "must be > 0"),
    ("static_load", -3383.29425, "must be > 0"),
    ("static_load", NAN, "must be finite"),
    ("static_load", INF, "must be finite"),
    ("road_delay", -1e-3, "must be >= 0"),
    ("road_delay", NAN, "must be finite"),
    ("road_phase", INF, "must be finite"),
]


@pytest.fixture
def corner_init_mode(make):
    inst = make(fmu=fmi2.corner_fmu_file())
    assert inst.ok, inst.log.last()
    assert inst.setup(0.0, 15.0) == OK and inst.enter() == OK
    return inst


@pytest.mark.parametrize("name, value, reason", CORNER_BAD_VALUES, ids=[f"{n}={v}" for n, v, _ in CORNER_BAD_VALUES])
def test_corner_bad_value_is_refused_naming_variable_and_value(corner_init_mode, name, value, reason):
    inst = corner_init_mode
    before = inst.snapshot()
    assert inst.set(**{name: value}) == ERROR
    message = last_error(inst)
    assert message.startswith(f"fmi2SetReal: invalid value {rust(value)} for `{name}`: "), message
    assert reason in message, message
    assert inst.snapshot() == before
    assert inst.machine_state() == "initializationMode"
    assert inst.exit() == OK  # nothing was applied
    assert inst.get("static_load", "road_delay", "road_phase", "body_displacement", "body_velocity") == \
        [3383.29425, 0.0, 0.0, 0.0, 0.0]


@pytest.mark.parametrize("name, value", [("body_displacement", NAN), ("body_velocity", INF),
                                         ("body_displacement", -1e4)])
def test_corner_bad_body_input_while_stepping(make, name, value):
    """Refused in stepComplete too: nothing changes, and the instance steps on."""
    inst = make(fmu=fmi2.corner_fmu_file())
    inst.initialize(stop=15.0)
    assert inst.set(body_displacement=0.01, body_velocity=0.1) == OK
    assert inst.step(0.01) == OK
    before = inst.snapshot()
    assert inst.set(**{name: value}) == ERROR
    assert f"invalid value {rust(value)} for `{name}`" in last_error(inst)
    assert inst.snapshot() == before
    assert inst.step(0.01) == OK
    assert all(math.isfinite(v) for v in inst.get("body_force", "x_t", "suspension_deflection"))


# Admissible alone, refused when the corner's simulation is built.
CORNER_BAD_AT_INITIALIZATION = [
    pytest.param({"road": 0, "road_delay": 0.1}, "road_delay", "applies to the built-in roads", id="road_delay, road=0"),
    pytest.param({"static_load": 1e-7}, "static_load", "exceed the numerical limit", id="static_load=1e-7"),
]


@pytest.mark.parametrize("values, name, reason", CORNER_BAD_AT_INITIALIZATION)
def test_corner_bad_combination_is_refused_at_initialization(corner_init_mode, values, name, reason):
    inst = corner_init_mode
    assert inst.set(**values) == OK
    assert inst.exit() == ERROR
    message = last_error(inst)
    assert message.startswith("fmi2ExitInitializationMode: invalid "), message
    assert f"`{name}`" in message and reason in message, message
    assert inst.machine_state() == "initializationMode"
    assert inst.set(road=1, road_delay=0.0, static_load=3383.29425) == OK
    assert inst.exit() == OK


# The chassis's FMU (tdvass-chassis.fmu, the same library under the
# chassis's GUID): the four corners' forces and the body's parameters.
CHASSIS_BAD_VALUES = [
    ("force_fl", NAN, "must be finite"),
    ("force_fr", INF, "must be finite"),
    ("force_rl", -INF, "must be finite"),
    ("force_rr", NAN, "must be finite"),
    ("mass", 0.0, "must be > 0"),
    ("mass", -1380.0, "must be > 0"),
    ("mass", NAN, "must be finite"),
    ("pitch_inertia", 0.0, "must be > 0"),
    ("pitch_inertia", -2332.2, "must be > 0"),
    ("pitch_inertia", INF, "must be finite"),
    ("roll_inertia", 0.0, "must be > 0"),
    ("roll_inertia", -400.0, "must be > 0"),
    ("roll_inertia", NAN, "must be finite"),
    ("a", -1.3, "must be >= 0"),
    ("a", NAN, "must be finite"),
    ("b", INF, "must be finite"),
    ("track_front", 0.0, "must be > 0"),
    ("track_rear", -1.5, "must be > 0"),
    ("track_rear", NAN, "must be finite"),
    ("seat_x", NAN, "must be finite"),
    ("seat_y", -INF, "must be finite"),
]
CHASSIS_START = {"mass": 1380.0, "a": 1.3, "b": 1.3, "track_front": 1.5, "track_rear": 1.5,
                 "pitch_inertia": 2332.2000000000003, "roll_inertia": 400.0, "seat_x": 0.3, "seat_y": 0.35,
                 "force_fl": 0.0, "force_fr": 0.0, "force_rl": 0.0, "force_rr": 0.0}


@pytest.fixture
def chassis_init_mode(make):
    inst = make(fmu=fmi2.chassis_fmu_file())
    assert inst.ok, inst.log.last()
    assert inst.setup(0.0, 15.0) == OK and inst.enter() == OK
    return inst


@pytest.mark.parametrize("name, value, reason", CHASSIS_BAD_VALUES,
                         ids=[f"{n}={v}" for n, v, _ in CHASSIS_BAD_VALUES])
def test_chassis_bad_value_is_refused_naming_variable_and_value(chassis_init_mode, name, value, reason):
    inst = chassis_init_mode
    before = inst.snapshot()
    assert inst.set(**{name: value}) == ERROR
    message = last_error(inst)
    assert message.startswith(f"fmi2SetReal: invalid value {rust(value)} for `{name}`: "), message
    assert reason in message, message
    assert inst.snapshot() == before
    assert inst.machine_state() == "initializationMode"
    assert inst.exit() == OK  # nothing was applied
    assert inst.get(*CHASSIS_START) == list(CHASSIS_START.values())
    assert inst.step(0.01) == OK


@pytest.mark.parametrize("name, value", [("force_fl", NAN), ("force_fr", -INF), ("force_rr", INF)])
def test_chassis_bad_force_while_stepping(make, name, value):
    """Refused in stepComplete too: nothing changes, and the instance steps on."""
    inst = make(fmu=fmi2.chassis_fmu_file())
    inst.initialize(stop=15.0)
    assert inst.set(force_fl=500.0, force_rr=-200.0) == OK
    assert inst.step(0.01) == OK
    before = inst.snapshot()
    assert inst.set(**{name: value}) == ERROR
    assert f"invalid value {rust(value)} for `{name}`" in last_error(inst)
    assert inst.snapshot() == before
    assert inst.step(0.01) == OK
    values = inst.get("heave", "pitch", "roll", "heave_acceleration", "displacement_fl", "seat_vibration_dose_value")
    assert all(math.isfinite(v) for v in values), values
    assert values[0] > 0.0


def test_chassis_zero_wheelbase_is_refused_at_initialization(chassis_init_mode):
    """a = 0 and b = 0 pass each value's check; the wheelbase is refused
    when the chassis is built, naming b."""
    inst = chassis_init_mode
    assert inst.set(a=0.0, b=0.0) == OK
    assert inst.exit() == ERROR
    message = last_error(inst)
    assert message.startswith("fmi2ExitInitializationMode: invalid value 0 for parameter `b`: "), message
    assert "the wheelbase a + b must be positive" in message, message
    assert inst.machine_state() == "initializationMode"
    assert inst.set(b=1.3) == OK
    assert inst.exit() == OK
    assert inst.set(force_rl=100.0) == OK
    assert inst.step(0.01) == OK
    assert inst.get("pitch")[0] < 0.0


def test_tuning_the_gain_beyond_the_limit_while_simulating(initialized):
    inst = initialized()
    assert inst.set(g=1e13) == ERROR
    assert "invalid combination `g` = 10000000000000 over `m_h` = 4.05" in last_error(inst)
    assert inst.get("g") == [5386.0]
    assert inst.step(0.01) == OK


def test_input_derivative_values(initialized):
    inst = initialized(road=0)
    lib, vr = inst.lib, array(c_uint, [inst.vr["x_g"]])
    for order, value, expected in [(1, NAN, "must be finite"), (1, 1e7, "exceeds 1e6"),
                                   (0, 1.0, "invalid derivative order 0")]:
        assert lib.fmi2SetRealInputDerivatives(inst.c, vr, 1, array(c_int, [order]), array(c_double, [value])) == ERROR
        assert expected in last_error(inst)
    other = array(c_uint, [inst.vr["g"]])
    assert lib.fmi2SetRealInputDerivatives(inst.c, other, 1, array(c_int, [1]), array(c_double, [1.0])) == ERROR
    assert "`g` is not an input" in last_error(inst)
    assert inst.step(0.1) == OK
    assert inst.get("road_displacement") == [0.0]


def test_output_derivative_orders(initialized):
    inst = initialized()
    vr = array(c_uint, [inst.vr["x_s"]])
    out = (c_double * 1)()
    assert inst.lib.fmi2GetRealOutputDerivatives(inst.c, vr, 1, array(c_int, [2]), out) == ERROR
    assert "maxOutputDerivativeOrder = 1" in last_error(inst)
    g = array(c_uint, [inst.vr["g"]])
    assert inst.lib.fmi2GetRealOutputDerivatives(inst.c, g, 1, array(c_int, [1]), out) == ERROR


def test_directional_derivative_with_huge_seed(initialized):
    inst = initialized()
    assert inst.step(0.3) == OK
    unknown = array(c_uint, [inst.vr["body_acceleration"]])
    known = array(c_uint, [inst.vr["x_s"]])
    out = (c_double * 1)(-7.0)
    assert inst.lib.fmi2GetDirectionalDerivative(inst.c, unknown, 1, known, 1, array(c_double, [1e308]), out) == ERROR
    assert "not finite" in last_error(inst)
    assert math.isfinite(out[0])
    assert inst.lib.fmi2GetDirectionalDerivative(inst.c, unknown, 1, known, 1, array(c_double, [NAN]), out) == ERROR


# ------------------------------------------------------------------ steps


@pytest.mark.parametrize(
    "t, h, expected",
    [
        (0.0, 0.0, "invalid communicationStepSize 0: must be finite and > 0"),
        (0.0, -1e-3, "invalid communicationStepSize -0.001: must be finite and > 0"),
        (0.0, NAN, "invalid communicationStepSize NaN: must be finite and > 0"),
        (0.0, INF, "invalid communicationStepSize inf: must be finite and > 0"),
        (0.5, 0.1, "currentCommunicationPoint 0.5 does not match the FMU time 0"),
        (-0.1, 0.1, "currentCommunicationPoint -0.1 does not match the FMU time 0"),
        (NAN, 0.1, "currentCommunicationPoint NaN does not match the FMU time 0"),
        (0.0, 15.5, "a step of 15.5 s from 0 s ends at 15.5 s, past the stop time 15 s"),
    ],
)
def test_bad_do_step_is_refused_and_changes_nothing(initialized, t, h, expected):
    inst = initialized()
    assert inst.lib.fmi2DoStep(inst.c, t, h, 1) == ERROR
    assert last_error(inst) == f"fmi2DoStep: {expected}"
    assert inst.machine_state() == "stepComplete"
    assert inst.real_status() == (OK, 0.0)
    assert inst.step(0.01) == OK


def test_step_past_the_stop_time_after_reaching_it(initialized):
    inst = initialized(stop=0.02)
    assert inst.step(0.01) == OK and inst.step(0.01) == OK
    assert inst.step(0.001) == ERROR
    assert "past the stop time 0.02 s" in last_error(inst)


# ------------------------------------------------------------- FMU states


def test_fmu_state_null_arguments(initialized):
    inst = initialized()
    lib = inst.lib
    assert lib.fmi2GetFMUstate(inst.c, None) == ERROR
    assert last_error(inst) == "fmi2GetFMUstate: FMUstate is NULL while its length is 1"
    assert lib.fmi2SetFMUstate(inst.c, None) == ERROR
    assert last_error(inst) == "fmi2SetFMUstate: FMUstate is NULL"
    assert lib.fmi2FreeFMUstate(inst.c, None) == OK
    null_state = c_void_p()
    assert lib.fmi2FreeFMUstate(inst.c, byref(null_state)) == OK
    status, state = inst.get_state()
    assert lib.fmi2SerializedFMUstateSize(inst.c, state, None) == ERROR
    assert lib.fmi2SerializedFMUstateSize(inst.c, None, byref(c_size_t())) == ERROR
    assert lib.fmi2DeSerializeFMUstate(inst.c, None, 10, byref(c_void_p())) == ERROR
    assert last_error(inst) == "fmi2DeSerializeFMUstate: serializedState is NULL while its length is 10"
    data = inst.serialize(state)
    buf = (c_char * len(data)).from_buffer_copy(data)
    assert lib.fmi2DeSerializeFMUstate(inst.c, buf, len(data), None) == ERROR
    assert lib.fmi2SerializeFMUstate(inst.c, state, None, len(data)) == ERROR
    small = (c_char * 8)()
    assert lib.fmi2SerializeFMUstate(inst.c, state, small, 8) == ERROR
    assert f"the buffer has 8 bytes, the state needs {len(data)}" in last_error(inst)
    assert bytes(small) == b"\0" * 8


@pytest.fixture
def serialized(initialized):
    inst = initialized()
    assert inst.step(0.25) == OK
    status, state = inst.get_state()
    assert status == OK
    return inst, inst.serialize(state)


def refused_state(inst, data, expected):
    before = inst.get("x_s", "rms_body_acceleration")
    status, state = inst.deserialize(data)
    assert status == ERROR and not state.value
    message = last_error(inst)
    assert message.startswith("fmi2DeSerializeFMUstate: invalid serialized FMU state: "), message
    assert expected in message, message
    assert inst.get("x_s", "rms_body_acceleration") == before


def test_deserialize_empty(serialized):
    inst, _ = serialized
    refused_state(inst, b"", "not a tdvass FMU state (0 bytes")


@pytest.mark.parametrize("fraction", [0.01, 0.1, 0.5, 0.9, 0.999])
def test_deserialize_truncated(serialized, fraction):
    inst, data = serialized
    cut = max(int(len(data) * fraction), 9)
    header, _ = fmi2.serialized_fields(data)
    refused_state(inst, data[:cut], "truncated" if cut < header else "payload of")


@pytest.mark.parametrize("position", [0, 9, 13, 20, 60, 100, 0.5, 0.75, -1])
def test_deserialize_bit_flipped(serialized, position):
    inst, data = serialized
    at = int(position * len(data)) if isinstance(position, float) else position % len(data)
    flipped = bytearray(data)
    flipped[at] ^= 0x04
    refused_state(inst, bytes(flipped), "")


@pytest.mark.parametrize("version", [1, 2, 3, 4, 5, 8])
def test_deserialize_wrong_version(serialized, version):
    # States of the earlier versions (before the RMS time integral, the FMI
    # 3.0 settings and the metrics, the tolerance, the tire's contact law,
    # the Model Exchange model) and an unknown version (version 6, before
    # the bonds' input history, is still read).
    inst, data = serialized
    refused_state(inst, data[:8] + version.to_bytes(4, "little") + data[12:], f"format version {version} is not supported")


def test_deserialize_other_guid(serialized):
    inst, data = serialized
    other = data.replace(fmi2.guid().encode(), b"{00000000-0000-0000-0000-000000000000}")
    refused_state(inst, other, "written by the FMU with GUID {00000000-0000-0000-0000-000000000000}")


def test_deserialize_checksum_valid_but_negative_mass(serialized):
    inst, data = serialized
    at, _ = fmi2.serialized_fields(data)
    # payload: machine state (1), number of settings (4), then (vr u32, value u64); m_s is vr 2.
    m_s = at + 1 + 4 + 12 + 4
    assert int.from_bytes(data[m_s - 4 : m_s], "little") == inst.vr["m_s"]
    forged = bytearray(data)
    forged[m_s : m_s + 8] = ctypes.c_uint64.from_buffer_copy(ctypes.c_double(-1.0)).value.to_bytes(8, "little")
    refused_state(inst, fmi2.reseal(forged), "invalid value -1 for `m_s`")


def test_set_fmu_state_of_another_instance_is_refused(initialized):
    a = initialized()
    b = initialized(g=1000.0, road=2)
    assert a.step(0.5) == OK
    status, state = a.get_state()
    assert b.step(0.1) == OK
    before = b.get("x_s", "g")
    assert b.lib.fmi2SetFMUstate(b.c, state) == ERROR
    assert "was not created by this instance or was already freed" in last_error(b)
    assert b.get("x_s", "g") == before
    assert b.lib.fmi2FreeFMUstate(b.c, byref(state)) == ERROR
    assert state.value  # not freed, still a's
    assert a.lib.fmi2FreeFMUstate(a.c, byref(state)) == OK and not state.value


def test_state_moves_between_instances_through_serialization(initialized):
    """Decision: SetFMUstate takes only an instance's own states; moving one
    goes through serialization, which carries every parameter."""
    a = initialized(g=2000.0, tau=0.01)
    b = initialized()
    assert a.step(0.5) == OK
    status, state = a.get_state()
    data = a.serialize(state)
    status, moved = b.deserialize(data)
    assert status == OK
    assert b.lib.fmi2SetFMUstate(b.c, moved) == OK
    assert b.get("g", "tau") == [2000.0, 0.01]
    for inst in (a, b):
        inst.time = 0.5
        assert inst.step(0.5) == OK
    assert a.get(*OUT) == b.get(*OUT)


def test_double_free_of_an_fmu_state(initialized):
    inst = initialized()
    status, state = inst.get_state()
    copy = c_void_p(state.value)
    assert inst.lib.fmi2FreeFMUstate(inst.c, byref(state)) == OK
    assert inst.lib.fmi2FreeFMUstate(inst.c, byref(copy)) == ERROR
    assert inst.lib.fmi2SetFMUstate(inst.c, copy) == ERROR


OUT = ["x_s", "v_s", "x_h", "v_h", "x_t", "v_t", "body_acceleration", "suspension_deflection", "tire_deflection",
       "road_displacement", "control_force", "rms_body_acceleration", "rms_suspension_deflection",
       "rms_tire_deflection", "objective"]


def test_refused_calls_do_not_disturb_the_results(initialized):
    """A run sprinkled with refused calls gives bit-identical outputs."""
    clean, noisy = initialized(), initialized()
    for k in range(20):
        for bad in (lambda: noisy.lib.fmi2DoStep(noisy.c, noisy.time + 1.0, 0.01, 1),
                    lambda: noisy.set(m_s=1.0), lambda: noisy.set(g=NAN),
                    lambda: noisy.deserialize(b"garbage")[0], lambda: noisy.lib.fmi2CancelStep(noisy.c)):
            assert bad() == ERROR
        assert clean.step(0.05) == OK and noisy.step(0.05) == OK
    assert clean.get(*OUT) == noisy.get(*OUT)


@pytest.mark.parametrize("start", [-4.3180364477547035e42, 1e300, 5e8])
def test_start_time_too_large_for_the_internal_step(make, start):
    """Found by the api_sequence fuzzer: at |t| >> step the grid times stop
    resolving steps (the solver looped forever); refused at initialization."""
    inst = make()
    assert inst.setup(start, None) == OK and inst.set(max_internal_step=1e-4) == OK and inst.enter() == OK
    assert inst.exit() == ERROR
    message = last_error(inst)
    assert message.startswith(f"fmi2ExitInitializationMode: startTime {rust(start)} s is too large for the internal "
                              "step 1e-4 s"), message
    assert inst.machine_state() == "initializationMode"


def test_large_start_time_within_the_limit(make):
    inst = make()
    inst.initialize(start=4e8)
    inst.time = 4e8
    assert inst.step(0.01) == OK
