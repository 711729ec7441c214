"""Bad input to the real FMI 3.0 shared library: every case asserts the
exact status, the log message where there is an instance to log through,
that a refused call changed nothing (the serialized state of the instance
is bit-identical before and after), and (fixture teardown) that the
process and the library are still alive. One file per interface on purpose
(the fixtures load the library once): hence its length."""

import ctypes
import math
from ctypes import byref, c_bool, c_char, c_double, c_int, c_size_t, c_uint32, c_uint64, c_void_p

import pytest
from conftest import rust

import fmi2
import fmi3
from fmi2 import array
from fmi3 import ERROR, OK, WARNING

NAN, INF = float("nan"), float("inf")


def last_error(inst):
    status, category, message = inst.log.last()
    assert status == ERROR and category == "logStatusError", inst.log.last()
    return message


# ------------------------------------------------------------ NULL instance

_vr = array(c_uint32, [31])
_out = (c_double * 4)()
_u64 = (c_uint64 * 4)()
_bool = (c_bool * 4)()
_int = (c_int * 4)()
_buf = (c_char * 64)()
_size = c_size_t()
_slot = c_void_p()
_t = c_bool()
_time = c_double()

# The arguments after the instance, valid apart from the instance.
NULL_INSTANCE_CALLS = {
    "fmi3SetDebugLogging": (True, 0, None),
    "fmi3EnterInitializationMode": (False, 0.0, 0.0, True, 15.0),
    "fmi3ExitInitializationMode": (),
    "fmi3EnterEventMode": (),
    "fmi3Terminate": (),
    "fmi3Reset": (),
    **{name: (_vr, 1, _buf, 1) for name in fmi3.VALUE_TYPES},
    "fmi3GetBinary": (_vr, 1, byref(_size), _buf, 1),
    "fmi3SetBinary": (_vr, 1, byref(_size), _buf, 1),
    "fmi3GetClock": (_vr, 1, _bool),
    "fmi3SetClock": (_vr, 1, _bool),
    "fmi3GetNumberOfVariableDependencies": (39, byref(_size)),
    "fmi3GetVariableDependencies": (39, _u64, _vr, _u64, _int, 1),
    "fmi3GetFMUState": (byref(_slot),),
    "fmi3SetFMUState": (None,),
    "fmi3FreeFMUState": (byref(_slot),),
    "fmi3SerializedFMUStateSize": (None, byref(_size)),
    "fmi3SerializeFMUState": (None, _buf, 64),
    "fmi3DeserializeFMUState": (_buf, 64, byref(_slot)),
    "fmi3GetDirectionalDerivative": (_vr, 1, _vr, 1, _out, 1, _out, 1),
    "fmi3GetAdjointDerivative": (_vr, 1, _vr, 1, _out, 1, _out, 1),
    "fmi3EnterConfigurationMode": (),
    "fmi3ExitConfigurationMode": (),
    "fmi3GetIntervalDecimal": (_vr, 1, _out, _int),
    "fmi3GetIntervalFraction": (_vr, 1, _u64, _u64, _int),
    "fmi3GetShiftDecimal": (_vr, 1, _out),
    "fmi3GetShiftFraction": (_vr, 1, _u64, _u64),
    "fmi3SetIntervalDecimal": (_vr, 1, _out),
    "fmi3SetIntervalFraction": (_vr, 1, _u64, _u64),
    "fmi3SetShiftDecimal": (_vr, 1, _out),
    "fmi3SetShiftFraction": (_vr, 1, _u64, _u64),
    "fmi3EvaluateDiscreteStates": (),
    "fmi3UpdateDiscreteStates": (byref(_t), byref(_t), byref(_t), byref(_t), byref(_t), byref(_time)),
    "fmi3EnterContinuousTimeMode": (),
    "fmi3CompletedIntegratorStep": (True, byref(_t), byref(_t)),
    "fmi3SetTime": (0.0,),
    "fmi3SetContinuousStates": (_out, 1),
    "fmi3GetContinuousStateDerivatives": (_out, 1),
    "fmi3GetEventIndicators": (_out, 1),
    "fmi3GetContinuousStates": (_out, 1),
    "fmi3GetNominalsOfContinuousStates": (_out, 1),
    "fmi3GetNumberOfEventIndicators": (byref(_size),),
    "fmi3GetNumberOfContinuousStates": (byref(_size),),
    "fmi3GetOutputDerivatives": (_vr, 1, _int, _out, 1),
    "fmi3DoStep": (0.0, 0.001, False, byref(_t), byref(_t), byref(_t), byref(_time)),
    "fmi3EnterStepMode": (),
    "fmi3ActivateModelPartition": (1, 0.0),
}
WITHOUT_INSTANCE = ["fmi3GetVersion", "fmi3InstantiateModelExchange", "fmi3InstantiateCoSimulation",
                    "fmi3InstantiateScheduledExecution", "fmi3FreeInstance"]


def test_every_exported_function_has_a_case(lib3):
    exported = fmi3.exported_functions()
    assert len(exported) == 75
    assert sorted([*NULL_INSTANCE_CALLS, *WITHOUT_INSTANCE]) == exported
    for name in exported:
        assert getattr(lib3, name).restype is not None or name == "fmi3FreeInstance"


@pytest.mark.parametrize("function", sorted(NULL_INSTANCE_CALLS))
def test_null_instance_is_refused(lib3, function):
    assert getattr(lib3, function)(None, *NULL_INSTANCE_CALLS[function]) == ERROR


@pytest.mark.parametrize("function", ["fmi3Terminate", "fmi3DoStep", "fmi3GetFloat64", "fmi3FreeFMUState",
                                      "fmi3SetTime", "fmi3EnterConfigurationMode"])
def test_foreign_pointer_as_instance_is_refused(lib3, function):
    """A pointer to memory that is not an instance (zeros) is recognised."""
    fake = (ctypes.c_uint64 * 16)()
    assert getattr(lib3, function)(ctypes.addressof(fake), *NULL_INSTANCE_CALLS[function]) == ERROR
    lib3.fmi3FreeInstance(ctypes.addressof(fake))  # ignored, no crash
    assert list(fake) == [0] * 16


def test_an_fmi2_instance_is_not_an_fmi3_instance(lib, lib3):
    """An instance of the FMI 2.0 library passed to the FMI 3.0 one is
    refused and left intact."""
    inst = fmi2.Instance(lib)
    assert inst.ok
    assert lib3.fmi3Terminate(inst.c) == ERROR
    assert lib3.fmi3DoStep(inst.c, *NULL_INSTANCE_CALLS["fmi3DoStep"]) == ERROR
    lib3.fmi3FreeInstance(inst.c)  # ignored
    assert inst.machine_state() == "instantiated"
    inst.free()


def test_functions_without_an_instance(lib3):
    lib3.fmi3FreeInstance(None)
    assert lib3.fmi3GetVersion() == b"3.0"
    # NULL strings and no logger: NULL, nothing logged anywhere, no crash.
    assert not lib3.fmi3InstantiateCoSimulation(None, None, None, False, False, False, False, None, 0, None, None,
                                                None)
    assert not lib3.fmi3InstantiateModelExchange(None, None, None, False, False, None, None)
    assert not lib3.fmi3InstantiateScheduledExecution(None, None, None, False, False, None, None, None, None,
                                                      None)


# --------------------------------------------------------------- instantiate


def refused_instantiation(lib3, expected, **kwargs):
    log = fmi3.Log()
    inst = fmi3.Instance(lib3, log=log, **kwargs)
    assert not inst.ok
    assert len(log.messages) == 1, log.messages
    status, category, message = log.messages[0]
    assert status == ERROR and category == "logStatusError"
    assert message.startswith("fmi3InstantiateCoSimulation: ") and expected in message, message


def test_wrong_instantiation_token(lib3):
    token = fmi3.instantiation_token()
    refused_instantiation(lib3, f"instantiationToken {{00000000-0000-0000-0000-000000000000}} does not match this "
                          f"FMU's token {token}", token=b"{00000000-0000-0000-0000-000000000000}")


def test_the_fmi2_guid_is_not_the_instantiation_token(lib3):
    assert fmi2.guid() != fmi3.instantiation_token()
    refused_instantiation(lib3, f"instantiationToken {fmi2.guid()} does not match", token=fmi2.guid().encode())


@pytest.mark.parametrize("token", [b"", fmi3.instantiation_token().lower().encode() + b" ", b"{x}" * 100])
def test_malformed_instantiation_tokens(lib3, token):
    refused_instantiation(lib3, "does not match", token=token)


def test_null_instantiation_token(lib3):
    refused_instantiation(lib3, "instantiationToken is NULL", token=None)


def test_empty_and_null_instance_name(lib3):
    refused_instantiation(lib3, "instanceName is empty", name=b"")
    refused_instantiation(lib3, "instanceName is NULL", name=None)


def test_event_mode_used(lib3):
    refused_instantiation(lib3, "eventModeUsed = true, but this FMU has no event mode", event_mode=True)


def test_required_intermediate_variables(lib3, make3):
    vr = fmi3.variables()
    refused_instantiation(lib3, "`g` (value reference 10) is not available in intermediate updates",
                          required=[vr["g"][0]])
    refused_instantiation(lib3, "requiredIntermediateVariables: unknown value reference 9999",
                          required=[vr["x_s"][0], 9999])
    assert make3(required=[vr["x_s"][0], vr["x_g"][0]]).ok


def test_required_intermediate_variables_null_with_a_length(lib3):
    log = fmi3.Log()
    token = fmi3.instantiation_token().encode()
    assert not lib3.fmi3InstantiateCoSimulation(b"a", token, None, False, False, False, False, None, 3, log.key,
                                                fmi3.LOGGER, None)
    assert log.messages == [(ERROR, "logStatusError", "fmi3InstantiateCoSimulation: requiredIntermediateVariables "
                                                      "is NULL while its length is 3")]


def test_model_exchange_instantiation_makes_an_instance(make3):
    """fmi3InstantiateModelExchange makes an instance (since Model Exchange
    was added), without an error logged."""
    inst = make3(model_exchange=True)
    assert inst.ok
    assert not [m for m in inst.log.messages if m[0] != OK], inst.log.messages
    assert inst.machine_state() == "Instantiated"


@pytest.mark.parametrize("token, expected", [(b"{00000000-0000-0000-0000-000000000000}", "does not match"),
                                             (None, "instantiationToken is NULL")])
def test_model_exchange_instantiation_checks_the_token(lib3, token, expected):
    log = fmi3.Log()
    inst = fmi3.Instance(lib3, log=log, token=token, model_exchange=True)
    assert not inst.ok
    assert len(log.messages) == 1, log.messages
    status, category, message = log.messages[0]
    assert status == ERROR and category == "logStatusError"
    assert message.startswith("fmi3InstantiateModelExchange: ") and expected in message, message


def test_scheduled_execution_is_refused(lib3):
    log = fmi3.Log()
    token = fmi3.instantiation_token().encode()
    instance = lib3.fmi3InstantiateScheduledExecution(b"a", token, None, False, True, log.key, fmi3.LOGGER, None,
                                                      None, None)
    assert not instance
    assert len(log.messages) == 1, log.messages
    status, category, message = log.messages[0]
    assert (status, category) == (ERROR, "logStatusError")
    assert message.startswith("fmi3InstantiateScheduledExecution: Scheduled Execution is not supported"), message
    # The FMU implements Model Exchange too: the reason must not deny it.
    assert "Co-Simulation only" not in message, message


MODEL_EXCHANGE_FUNCTIONS = ["fmi3EnterEventMode", "fmi3SetTime", "fmi3GetContinuousStates",
                            "fmi3UpdateDiscreteStates", "fmi3EnterContinuousTimeMode",
                            "fmi3CompletedIntegratorStep", "fmi3SetContinuousStates",
                            "fmi3GetContinuousStateDerivatives", "fmi3GetEventIndicators",
                            "fmi3GetNominalsOfContinuousStates", "fmi3GetNumberOfContinuousStates",
                            "fmi3GetNumberOfEventIndicators"]


@pytest.mark.parametrize("function", MODEL_EXCHANGE_FUNCTIONS)
def test_model_exchange_functions_in_step_mode_are_refused_by_the_state_table(initialized3, function):
    """A Co-Simulation instance in Step Mode refuses every Model Exchange
    function, naming the state; nothing changes."""
    inst = initialized3()
    before = inst.snapshot()
    args = NULL_INSTANCE_CALLS[function]
    if function in ("fmi3SetContinuousStates", "fmi3GetContinuousStates", "fmi3GetContinuousStateDerivatives",
                    "fmi3GetNominalsOfContinuousStates"):
        args = ((c_double * fmi3.NX)(), fmi3.NX)
    assert getattr(inst.lib, function)(inst.c, *args) == ERROR
    assert last_error(inst) == f"{function}: not allowed in state Step Mode"
    assert inst.machine_state() == "Step Mode"
    assert inst.snapshot() == before


NOT_APPLICABLE = ["fmi3GetClock", "fmi3SetIntervalDecimal", "fmi3EnterStepMode", "fmi3ActivateModelPartition",
                  "fmi3EvaluateDiscreteStates"]


@pytest.mark.parametrize("model_exchange", [False, True], ids=["cs", "me"])
@pytest.mark.parametrize("function", NOT_APPLICABLE)
def test_functions_that_do_not_apply_are_refused_with_the_reason(make3, function, model_exchange):
    """Clocks, Scheduled Execution, Step Mode after Event Mode: refused in
    Step Mode (Co-Simulation) and in Event Mode (Model Exchange) alike."""
    inst = make3(model_exchange=model_exchange)
    inst.initialize(stop=15.0)
    state = inst.machine_state()
    assert state == ("Event Mode" if model_exchange else "Step Mode")
    before = inst.snapshot()
    assert getattr(inst.lib, function)(inst.c, *NULL_INSTANCE_CALLS[function]) == ERROR
    message = last_error(inst)
    assert message.startswith(f"{function}: "), message
    assert message.endswith("; this FMU implements Co-Simulation and Model Exchange, without clocks"), message
    assert inst.machine_state() == state
    assert inst.snapshot() == before


# ---------------------------------------------------------- arrays and NULL


@pytest.fixture
def init_mode(make3):
    inst = make3()
    assert inst.enter(0.0, 15.0) == OK
    return inst


GETTERS_SETTERS = ["fmi3GetFloat64", "fmi3GetInt32", "fmi3GetInt64", "fmi3GetUInt64", "fmi3GetBoolean",
                   "fmi3SetFloat64", "fmi3SetInt32", "fmi3SetInt64", "fmi3SetUInt64", "fmi3SetBoolean"]


@pytest.mark.parametrize("function", GETTERS_SETTERS)
def test_null_value_reference_array_with_a_length(init_mode, function):
    assert getattr(init_mode.lib, function)(init_mode.c, None, 2, _out, 2) == ERROR
    assert last_error(init_mode) == f"{function}: valueReferences is NULL while its length is 2"


@pytest.mark.parametrize("function", GETTERS_SETTERS)
def test_null_value_array_with_a_length(init_mode, function):
    vr = array(c_uint32, [init_mode.vr["m_s"]])
    assert getattr(init_mode.lib, function)(init_mode.c, vr, 1, None, 1) == ERROR
    assert last_error(init_mode) == f"{function}: values is NULL while its length is 1"


@pytest.mark.parametrize("function", GETTERS_SETTERS)
def test_empty_calls_with_null_arrays_are_ok(init_mode, function):
    assert getattr(init_mode.lib, function)(init_mode.c, None, 0, None, 0) == OK


def test_null_strings_of_set_debug_logging(make3):
    inst = make3()
    assert inst.lib.fmi3SetDebugLogging(inst.c, True, 2, None) == ERROR
    assert last_error(inst) == "fmi3SetDebugLogging: categories is NULL while its length is 2"
    categories = (ctypes.c_char_p * 2)(b"logEvents", None)
    assert inst.lib.fmi3SetDebugLogging(inst.c, True, 2, categories) == ERROR
    assert last_error(inst) == "fmi3SetDebugLogging: categories[1] is NULL"
    categories = (ctypes.c_char_p * 1)(b"logEverything")
    assert inst.lib.fmi3SetDebugLogging(inst.c, True, 1, categories) == ERROR
    assert "unknown log category `logEverything`" in last_error(inst)


def test_null_arrays_of_the_derivative_functions(initialized3):
    inst = initialized3()
    lib, c = inst.lib, inst.c
    vr = array(c_uint32, [inst.vr["x_s"]])
    one = array(c_double, [1.0])
    out = (c_double * 1)(-7.0)
    for function in ("fmi3GetDirectionalDerivative", "fmi3GetAdjointDerivative"):
        assert getattr(lib, function)(c, vr, 1, vr, 1, None, 1, out, 1) == ERROR
        assert last_error(inst) == f"{function}: seed is NULL while its length is 1"
        assert getattr(lib, function)(c, vr, 1, vr, 1, one, 1, None, 1) == ERROR
        assert last_error(inst) == f"{function}: sensitivity is NULL while its length is 1"
        assert getattr(lib, function)(c, vr, 1, vr, 1, one, 2, out, 1) == ERROR
        assert "nSeed = 2 and nSensitivity = 1, expected 1 and 1" in last_error(inst)
    assert out[0] == -7.0
    assert lib.fmi3GetOutputDerivatives(c, vr, 1, None, out, 1) == ERROR
    assert last_error(inst) == "fmi3GetOutputDerivatives: orders is NULL while its length is 1"
    assert lib.fmi3GetOutputDerivatives(c, vr, 1, array(c_int, [1]), out, 2) == ERROR
    assert last_error(inst) == "fmi3GetOutputDerivatives: nValues = 2 for 1 value references"


def test_dependencies_with_wrong_counts_and_null_arrays(initialized3):
    inst = initialized3()
    lib, c = inst.lib, inst.c
    tdd, x_g = inst.vr["tire_deflection"], inst.vr["x_g"]
    n = c_size_t(99)
    assert lib.fmi3GetNumberOfVariableDependencies(c, tdd, None) == ERROR
    assert last_error(inst) == "fmi3GetNumberOfVariableDependencies: nDependencies is NULL while its length is 1"
    # TDD depends on x_g and on the six plant states.
    assert lib.fmi3GetNumberOfVariableDependencies(c, tdd, byref(n)) == OK and n.value == 7
    assert lib.fmi3GetNumberOfVariableDependencies(c, inst.vr["g"], byref(n)) == ERROR
    assert "`g` is not an output" in last_error(inst)
    assert lib.fmi3GetNumberOfVariableDependencies(c, 9999, byref(n)) == ERROR
    assert last_error(inst) == "fmi3GetNumberOfVariableDependencies: unknown value reference 9999"
    arrays = [(c_size_t * 8)(), (c_uint32 * 8)(), (c_size_t * 8)(), (c_int * 8)()]
    assert lib.fmi3GetVariableDependencies(c, tdd, *arrays, 8) == ERROR
    assert "nDependencies = 8, but the variable has 7" in last_error(inst)
    assert lib.fmi3GetVariableDependencies(c, tdd, arrays[0], None, arrays[2], arrays[3], 7) == ERROR
    assert last_error(inst) == "fmi3GetVariableDependencies: independents is NULL while its length is 7"
    assert lib.fmi3GetVariableDependencies(c, tdd, *arrays, 7) == OK
    plant = [inst.vr[name] for name in ("x_s", "v_s", "x_h", "v_h", "x_t", "v_t")]
    assert list(arrays[1][:7]) == sorted(plant + [x_g])
    # fmi3Fixed (2) for the input's fixed factor, fmi3Dependent (5) for the states.
    kinds = dict(zip(arrays[1][:7], arrays[3][:7]))
    assert kinds == {vr: (2 if vr == x_g else 5) for vr in plant + [x_g]}


# ------------------------------------------------------ value references, types


@pytest.mark.parametrize("vr", [0, 1000, 9999, 2**31, 2**32 - 1])
def test_unknown_value_reference(init_mode, vr):
    status, _ = init_mode.get_float64([vr])
    assert status == ERROR
    assert last_error(init_mode) == f"fmi3GetFloat64: unknown value reference {vr} (for a Float64)"
    assert init_mode.set_values("fmi3SetFloat64", [vr], [1.0]) == ERROR
    assert init_mode.set_values("fmi3SetInt64", [vr], [1]) == ERROR
    assert last_error(init_mode) == f"fmi3SetInt64: unknown value reference {vr} (for a Int64)"


TYPE_MISMATCHES = [
    ("fmi3GetInt32", "variant", "Int64", "Int32"),  # an Enumeration is read as Int64
    ("fmi3GetFloat64", "road", "Int64", "Float64"),
    ("fmi3GetInt64", "road_seed", "Int32", "Int64"),
    ("fmi3GetUInt64", "variant", "Int64", "UInt64"),
    ("fmi3GetInt32", "root_count", "UInt64", "Int32"),
    ("fmi3GetBoolean", "g", "Float64", "Boolean"),
    ("fmi3GetFloat64", "stable", "Boolean", "Float64"),
    ("fmi3GetFloat32", "m_s", "Float64", "Float32"),
    ("fmi3GetInt8", "variant", "Int64", "Int8"),
    ("fmi3GetUInt32", "road_seed", "Int32", "UInt32"),
    ("fmi3GetString", "x_s", "Float64", "String"),
    ("fmi3SetInt32", "variant", "Int64", "Int32"),
    ("fmi3SetFloat64", "road_class", "Int64", "Float64"),
    ("fmi3SetInt64", "road_seed", "Int32", "Int64"),
    ("fmi3SetBoolean", "m_s", "Float64", "Boolean"),
    ("fmi3SetUInt16", "road_seed", "Int32", "UInt16"),
]


@pytest.mark.parametrize("function, name, actual, asked", TYPE_MISMATCHES,
                         ids=[f"{f}-{n}" for f, n, _, _ in TYPE_MISMATCHES])
def test_wrong_type_for_value_reference(init_mode, function, name, actual, asked):
    before = init_mode.snapshot()
    vr = init_mode.vr[name]
    if function.startswith("fmi3Get"):
        status, _ = init_mode.get_values(function, [vr])
    else:
        value = b"x" if asked == "String" else 1
        status = init_mode.set_values(function, [vr], [value])
    assert status == ERROR
    assert last_error(init_mode) == f"{function}: value reference {vr} is `{name}`, a {actual}, not a {asked}"
    assert init_mode.snapshot() == before


def test_binary_has_no_variable(init_mode):
    vr = array(c_uint32, [init_mode.vr["m_s"]])
    sizes, values = (c_size_t * 1)(), (c_void_p * 1)()
    assert init_mode.lib.fmi3GetBinary(init_mode.c, vr, 1, sizes, values, 1) == ERROR
    assert last_error(init_mode) == f"fmi3GetBinary: value reference {vr[0]} is `m_s`, a Float64, not a Binary"
    assert init_mode.lib.fmi3SetBinary(init_mode.c, vr, 1, sizes, values, 1) == ERROR


@pytest.mark.parametrize("n, expected", [
    (0, "0 values given for value references that hold more (`rightmost_roots` needs 6 from position 0)"),
    (1, "1 values given for value references that hold more (`rightmost_roots` needs 6 from position 0)"),
    (5, "5 values given for value references that hold more (`rightmost_roots` needs 6 from position 0)"),
    (7, "7 values given, the value references hold 6"),
    (12, "12 values given, the value references hold 6"),
])
def test_array_with_a_wrong_number_of_values(initialized3, n, expected):
    """rightmost_roots is a root_count x 2 array (root_count = 3): nValues
    must be 6."""
    inst = initialized3()
    roots = inst.vr["rightmost_roots"]
    status, values = inst.get_float64([roots], 6)
    assert status == OK and all(math.isfinite(v) for v in values)
    status, _ = inst.get_float64([roots], n)
    assert status == ERROR
    assert last_error(inst) == f"fmi3GetFloat64: {expected}"
    # With a scalar behind it: 6 + 1 values.
    status, both = inst.get_float64([roots, inst.vr["g"]], 7)
    assert status == OK and both == [*values, 5386.0]
    status, _ = inst.get_float64([inst.vr["g"], roots], 6)
    assert status == ERROR
    assert "`rightmost_roots` needs 6 from position 1" in last_error(inst)


def test_scalars_with_a_wrong_number_of_values(init_mode):
    vrs = [init_mode.vr["m_s"], init_mode.vr["m_h"]]
    assert init_mode.get_float64(vrs, 3)[0] == ERROR
    assert last_error(init_mode) == "fmi3GetFloat64: 3 values given, the value references hold 2"
    assert init_mode.lib.fmi3SetFloat64(init_mode.c, array(c_uint32, vrs), 2, array(c_double, [1.0]), 1) == ERROR
    assert last_error(init_mode) == "fmi3SetFloat64: 1 values given for 2 value references"
    assert init_mode.get_values("fmi3GetInt64", [init_mode.vr["variant"], init_mode.vr["road"]], 1)[0] == ERROR
    assert last_error(init_mode) == "fmi3GetInt64: 1 values given for 2 value references"
    assert init_mode.get("m_s", "m_h") == [345.0, 4.05]


def test_root_count_larger_than_the_roots_found(make3):
    """CS has 4 characteristic roots: asking for 16 is refused when read."""
    inst = make3()
    assert inst.set(root_count=16, variant=1) == OK
    assert inst.enter(0.0, 15.0) == OK and inst.exit() == OK
    assert inst.get_float64([inst.vr["rightmost_roots"]], 32)[0] == ERROR
    assert "`root_count` = 16 asks for more roots than were found" in last_error(inst)


def test_one_bad_reference_refuses_the_whole_call(init_mode):
    before = init_mode.snapshot()
    assert init_mode.set_values("fmi3SetFloat64", [init_mode.vr["g"], 9999], [1000.0, 1.0]) == ERROR
    assert init_mode.set_values("fmi3SetInt64", [init_mode.vr["variant"], init_mode.vr["road"]], [1, 7]) == ERROR
    assert init_mode.snapshot() == before
    assert init_mode.get("g") == [5386.0]


# --------------------------------------------------- causality, variability


@pytest.mark.parametrize("name, value, expected", [
    ("x_s", 1.0, "`x_s` is an output and cannot be set (value 1 refused)"),
    ("spectral_abscissa", -1.0, "`spectral_abscissa` is a calculated parameter and cannot be set"),
    ("rightmost_roots", 1.0, "`rightmost_roots` is a calculated parameter and cannot be set"),
    ("time", 1.0, "`time` is the independent variable and cannot be set (value 1 refused)"),
    ("m_s", 300.0, "`m_s` is a fixed parameter and cannot be changed after initialization"),
    ("root_count", 4, "`root_count` is a structural parameter: it can be set only before initialization"),
    ("variant", 1, "`variant` is a fixed parameter and cannot be changed after initialization"),
    ("stable", False, "`stable` is a calculated parameter and cannot be set"),
])
def test_what_cannot_be_set_in_step_mode(initialized3, name, value, expected):
    inst = initialized3()
    before = inst.snapshot()
    assert inst.set(**{name: value}) == ERROR
    assert expected in last_error(inst)
    assert inst.snapshot() == before
    assert inst.machine_state() == "Step Mode"


def test_configuration_mode_admits_structural_parameters_only(make3):
    inst = make3()
    assert inst.lib.fmi3EnterConfigurationMode(inst.c) == OK
    before = inst.snapshot()
    assert inst.set(g=1000.0) == ERROR
    assert last_error(inst) == ("fmi3SetFloat64: `g` is not a structural parameter: only those are accessible in "
                                "Configuration Mode")
    assert inst.get_values("fmi3GetInt64", [inst.vr["variant"]])[0] == ERROR
    assert inst.snapshot() == before
    assert inst.set(root_count=5) == OK
    assert inst.lib.fmi3ExitConfigurationMode(inst.c) == OK
    inst.initialize(stop=15.0)
    assert inst.get_values("fmi3GetUInt64", [inst.vr["root_count"]]) == (OK, [5])
    assert inst.get_float64([inst.vr["rightmost_roots"]], 10)[0] == OK


def test_intermediate_updates_admit_their_variables_only(make3):
    """Inside the callback: outputs are read and x_g set; other variables
    are refused naming why, and the step goes on."""
    results = []

    def on_update(inst, time, can_return_early):
        if results:
            return False
        g, x_s, x_g = inst.vr["g"], inst.vr["x_s"], inst.vr["x_g"]
        results.append(inst.get_float64([g])[0])
        results.append(last_error(inst))
        results.append(inst.set_values("fmi3SetFloat64", [g], [1000.0]))
        results.append(last_error(inst))
        results.append(inst.set_values("fmi3SetFloat64", [x_s], [1.0]))
        results.append(last_error(inst))
        results.append(inst.get_float64([x_s])[0])
        results.append(inst.set_values("fmi3SetFloat64", [x_g], [0.0]))
        return False

    inst = make3(intermediate=on_update)
    inst.initialize(stop=15.0, max_internal_step=1e-4)
    assert inst.step(0.001) == OK
    assert results == [
        ERROR, "fmi3GetFloat64: `g` is not accessible in this intermediate update (it is not an "
               "intermediate-update variable)",
        ERROR, "fmi3SetFloat64: `g` is not accessible in this intermediate update (it is not an "
               "intermediate-update variable)",
        ERROR, "fmi3SetFloat64: `x_s` is an output and cannot be set (value 1 refused)",
        OK, OK,
    ]
    assert inst.get("g") == [5386.0]


# ----------------------------------------------------- values out of range

BAD_VALUES = [
    ("fmi3SetFloat64", "m_s", -345.0, "must be > 0"),
    ("fmi3SetFloat64", "m_t", -INF, "must be finite"),
    ("fmi3SetFloat64", "m_s", NAN, "must be finite"),
    ("fmi3SetFloat64", "k_t", INF, "must be finite"),
    ("fmi3SetFloat64", "g", NAN, "must be finite"),
    ("fmi3SetFloat64", "tau", -2e-4, "must be >= 0"),
    ("fmi3SetFloat64", "tau", NAN, "must be finite"),
    ("fmi3SetFloat64", "max_internal_step", -1e-4, "must be >= 0"),
    ("fmi3SetFloat64", "road_amplitude", 1e4, "exceeds 1e3"),
    ("fmi3SetFloat64", "w_tdd", 1e300, "exceeds 1e12"),
    ("fmi3SetFloat64", "x_g", NAN, "must be finite"),
    ("fmi3SetFloat64", "x_g", 1e6, "exceeds 1e3"),
    ("fmi3SetFloat64", "intermediate_update_interval", -1.0, "must be >= 0"),
    ("fmi3SetFloat64", "intermediate_update_interval", NAN, "must be finite"),
    ("fmi3SetFloat64", "intermediate_update_interval", INF, "must be finite"),
    ("fmi3SetInt64", "variant", 0, "must be in 1..=3"),
    ("fmi3SetInt64", "variant", 4, "must be in 1..=3"),
    ("fmi3SetInt64", "variant", 2**40, "1 .. 3"),
    ("fmi3SetInt64", "variant", -(2**63), "1 .. 3"),
    ("fmi3SetInt64", "road", -1, "must be in 0..=3"),
    ("fmi3SetInt64", "road_class", 9, "must be in 1..=8"),
    ("fmi3SetInt32", "road_seed", -1, "must be in 0..=2147483647"),
    ("fmi3SetInt32", "input_extrapolation", 3, "must be in 0..=2"),
]


@pytest.mark.parametrize("function, name, value, reason", BAD_VALUES, ids=[f"{n}={v}" for _, n, v, _ in BAD_VALUES])
def test_bad_value_is_refused_naming_variable_and_value(init_mode, function, name, value, reason):
    before = init_mode.snapshot()
    assert init_mode.set_values(function, [init_mode.vr[name]], [value]) == ERROR
    message = last_error(init_mode)
    assert message.startswith(f"{function}: invalid value {rust(value)} for `{name}`: "), message
    assert reason in message, message
    assert init_mode.snapshot() == before
    assert init_mode.machine_state() == "Initialization Mode"
    assert init_mode.exit() == OK  # nothing was applied


@pytest.mark.parametrize("value, reason", [(0, "must be in 1..=16"), (17, "must be in 1..=16"),
                                           (2**32, "1 .. 16"), (2**64 - 1, "1 .. 16")])
def test_bad_structural_parameter_in_configuration_mode(make3, value, reason):
    inst = make3()
    assert inst.lib.fmi3EnterConfigurationMode(inst.c) == OK
    before = inst.snapshot()
    assert inst.set(root_count=value) == ERROR
    message = last_error(inst)
    assert message.startswith(f"fmi3SetUInt64: invalid value {value} for `root_count`: "), message
    assert reason in message, message
    assert inst.snapshot() == before
    assert inst.get_values("fmi3GetUInt64", [inst.vr["root_count"]]) == (OK, [3])


def test_bad_combination_is_refused_at_initialization(init_mode):
    assert init_mode.set(tau=1e4) == OK
    assert init_mode.exit() == ERROR
    message = last_error(init_mode)
    assert message.startswith("fmi3ExitInitializationMode: invalid "), message
    assert "`tau`" in message and "the delay needs more than 8388608 history nodes" in message, message
    assert init_mode.machine_state() == "Initialization Mode"
    assert init_mode.set(tau=2e-4) == OK
    assert init_mode.exit() == OK


# The corner's FMU (tdvass-corner-fmi3.fmu, the same library under the
# corner's instantiation token): its own parameters and body inputs.
CORNER_BAD_VALUES = [
    ("body_displacement", NAN, "must be finite"),
    ("body_displacement", -INF, "must be finite"),
    ("body_displacement", 1e6, "exceeds 1e3"),
    ("body_velocity", NAN, "must be finite"),
    ("body_velocity", INF, "must be finite"),
    ("body_velocity", -1e7, "exceeds 1e6"),
    ("static_load", 0.0, "must be > 0"),
    ("static_load", -1.0, "must be > 0"),
    ("static_load", NAN, "must be finite"),
    ("road_delay", -1e-3, "must be >= 0"),
    ("road_delay", INF, "must be finite"),
    ("road_phase", NAN, "must be finite"),
]


@pytest.fixture
def corner_init_mode(make3):
    inst = make3(fmu=fmi3.corner_fmu_file())
    assert inst.ok, inst.log.last()
    assert inst.enter(0.0, 15.0) == OK
    return inst


@pytest.mark.parametrize("name, value, reason", CORNER_BAD_VALUES, ids=[f"{n}={v}" for n, v, _ in CORNER_BAD_VALUES])
def test_corner_bad_value_is_refused_naming_variable_and_value(corner_init_mode, name, value, reason):
    inst = corner_init_mode
    before = inst.snapshot()
    assert inst.set_values("fmi3SetFloat64", [inst.vr[name]], [value]) == ERROR
    message = last_error(inst)
    assert message.startswith(f"fmi3SetFloat64: invalid value {rust(value)} for `{name}`: "), message
    assert reason in message, message
    assert inst.snapshot() == before
    assert inst.machine_state() == "Initialization Mode"
    assert inst.exit() == OK  # nothing was applied
    assert inst.get("static_load", "road_delay", "road_phase", "body_displacement", "body_velocity") == \
        [3383.29425, 0.0, 0.0, 0.0, 0.0]


@pytest.mark.parametrize("name, value", [("body_displacement", NAN), ("body_velocity", -INF),
                                         ("body_velocity", 1e7)])
def test_corner_bad_body_input_in_step_mode(make3, name, value):
    """Refused in Step Mode too: nothing changes, and the instance steps on."""
    inst = make3(fmu=fmi3.corner_fmu_file())
    inst.initialize(stop=15.0)
    assert inst.set(body_displacement=0.01, body_velocity=0.1) == OK
    assert inst.step(0.01) == OK
    before = inst.snapshot()
    assert inst.set(**{name: value}) == ERROR
    assert f"invalid value {rust(value)} for `{name}`" in last_error(inst)
    assert inst.snapshot() == before
    assert inst.step(0.01) == OK
    assert all(math.isfinite(v) for v in inst.get("body_force", "x_t", "suspension_deflection"))


def test_corner_road_delay_with_the_input_road_is_refused_at_initialization(corner_init_mode):
    inst = corner_init_mode
    assert inst.set(road=0, road_delay=0.1) == OK
    assert inst.exit() == ERROR
    message = last_error(inst)
    assert message.startswith("fmi3ExitInitializationMode: invalid "), message
    assert "`road_delay`" in message and "applies to the built-in roads" in message, message
    assert inst.machine_state() == "Initialization Mode"
    assert inst.set(road_delay=0.0) == OK
    assert inst.exit() == OK


# The chassis's FMU (tdvass-chassis-fmi3.fmu, the same library under the
# chassis's instantiation token): the corners' forces and the body's
# parameters.
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
def chassis_init_mode(make3):
    inst = make3(fmu=fmi3.chassis_fmu_file())
    assert inst.ok, inst.log.last()
    assert inst.enter(0.0, 15.0) == OK
    return inst


@pytest.mark.parametrize("name, value, reason", CHASSIS_BAD_VALUES,
                         ids=[f"{n}={v}" for n, v, _ in CHASSIS_BAD_VALUES])
def test_chassis_bad_value_is_refused_naming_variable_and_value(chassis_init_mode, name, value, reason):
    inst = chassis_init_mode
    before = inst.snapshot()
    assert inst.set_values("fmi3SetFloat64", [inst.vr[name]], [value]) == ERROR
    message = last_error(inst)
    assert message.startswith(f"fmi3SetFloat64: invalid value {rust(value)} for `{name}`: "), message
    assert reason in message, message
    assert inst.snapshot() == before
    assert inst.machine_state() == "Initialization Mode"
    assert inst.exit() == OK  # nothing was applied
    assert inst.get(*CHASSIS_START) == list(CHASSIS_START.values())
    assert inst.step(0.01) == OK


@pytest.mark.parametrize("name, value", [("force_fl", NAN), ("force_rl", INF), ("force_rr", -INF)])
def test_chassis_bad_force_in_step_mode(make3, name, value):
    """Refused in Step Mode too: nothing changes, and the instance steps on."""
    inst = make3(fmu=fmi3.chassis_fmu_file())
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
    assert message.startswith("fmi3ExitInitializationMode: invalid value 0 for parameter `b`: "), message
    assert "the wheelbase a + b must be positive" in message, message
    assert inst.machine_state() == "Initialization Mode"
    assert inst.set(b=1.3) == OK
    assert inst.exit() == OK
    assert inst.set(force_rl=100.0) == OK
    assert inst.step(0.01) == OK
    assert inst.get("pitch")[0] < 0.0


def test_derivatives_with_a_huge_seed(initialized3):
    inst = initialized3()
    assert inst.step(0.3) == OK
    unknown = array(c_uint32, [inst.vr["body_acceleration"]])
    known = array(c_uint32, [inst.vr["x_s"]])
    out = (c_double * 1)(-7.0)
    for function in ("fmi3GetDirectionalDerivative", "fmi3GetAdjointDerivative"):
        for seed in (1e308, NAN):
            status = getattr(inst.lib, function)(inst.c, unknown, 1, known, 1, array(c_double, [seed]), 1, out, 1)
            assert status == ERROR
            message = last_error(inst)
            assert message.startswith(f"{function}: ") and "finite" in message, message
            assert math.isfinite(out[0])


def test_output_derivative_orders(initialized3):
    inst = initialized3()
    vr = array(c_uint32, [inst.vr["x_s"]])
    out = (c_double * 1)()
    assert inst.lib.fmi3GetOutputDerivatives(inst.c, vr, 1, array(c_int, [2]), out, 1) == ERROR
    assert "maxOutputDerivativeOrder = 1" in last_error(inst)
    g = array(c_uint32, [inst.vr["g"]])
    assert inst.lib.fmi3GetOutputDerivatives(inst.c, g, 1, array(c_int, [1]), out, 1) == ERROR
    assert "`g` is not an output" in last_error(inst)


# ------------------------------------------------------------------ steps


@pytest.mark.parametrize(
    "t, h, expected",
    [
        (0.0, 0.0, "invalid communicationStepSize 0: must be finite and > 0"),
        (0.0, -1e-3, "invalid communicationStepSize -0.001: must be finite and > 0"),
        (0.0, NAN, "invalid communicationStepSize NaN: must be finite and > 0"),
        (0.0, INF, "invalid communicationStepSize inf: must be finite and > 0"),
        (0.0, -INF, "invalid communicationStepSize -inf: must be finite and > 0"),
        (0.5, 0.1, "currentCommunicationPoint 0.5 does not match the FMU time 0"),
        (-0.1, 0.1, "currentCommunicationPoint -0.1 does not match the FMU time 0"),
        (NAN, 0.1, "currentCommunicationPoint NaN does not match the FMU time 0"),
        (INF, 0.1, "currentCommunicationPoint inf does not match the FMU time 0"),
        (0.0, 15.5, "a step of 15.5 s from 0 s ends at 15.5 s, past the stop time 15 s"),
    ],
)
def test_bad_do_step_is_refused_and_changes_nothing(initialized3, t, h, expected):
    inst = initialized3()
    before = inst.snapshot()
    status, *_ = inst.do_step(t, h)
    assert status == ERROR
    assert last_error(inst) == f"fmi3DoStep: {expected}"
    assert inst.machine_state() == "Step Mode"
    assert inst.snapshot() == before
    assert inst.do_step(0.0, 0.01) == (OK, False, False, False, 0.01)


@pytest.mark.parametrize("pointer", ["eventHandlingNeeded", "terminateSimulation", "earlyReturn",
                                     "lastSuccessfulTime"])
def test_do_step_with_a_null_out_pointer(initialized3, pointer):
    inst = initialized3()
    before = inst.snapshot()
    keyword = {"eventHandlingNeeded": "event", "terminateSimulation": "terminate", "earlyReturn": "early",
               "lastSuccessfulTime": "last"}[pointer]
    status, *_ = inst.do_step(0.0, 0.01, **{keyword: None})
    assert status == ERROR
    assert last_error(inst) == f"fmi3DoStep: {pointer} is NULL while its length is 1"
    assert inst.snapshot() == before
    assert inst.step(0.01) == OK


def test_step_past_the_stop_time_after_reaching_it(initialized3):
    inst = initialized3(stop=0.02)
    assert inst.step(0.01) == OK and inst.step(0.01) == OK
    before = inst.snapshot()
    assert inst.step(0.001) == ERROR
    assert "past the stop time 0.02 s" in last_error(inst)
    assert inst.snapshot() == before


def test_huge_step_without_stop_time(initialized3):
    inst = initialized3(stop=None)
    assert inst.step(1e9) == ERROR
    assert "internal steps" in last_error(inst) and "per fmi3DoStep" in last_error(inst)


def test_early_return_requested_but_not_allowed_is_not_taken(make3):
    inst = make3(intermediate=lambda *_: True, early_return=False)
    inst.initialize(stop=15.0, max_internal_step=1e-4)
    assert inst.do_step(0.0, 0.001) == (OK, False, False, False, 0.001)
    assert len(inst.updates) == 9


@pytest.mark.parametrize("start", [-4.3180364477547035e42, 1e300, 5e8])
def test_start_time_too_large_for_the_internal_step(make3, start):
    inst = make3()
    assert inst.set(max_internal_step=1e-4) == OK
    assert inst.enter(start, None) == OK
    assert inst.exit() == ERROR
    message = last_error(inst)
    assert message.startswith(f"fmi3ExitInitializationMode: startTime {rust(start)} s is too large for the internal "
                              "step 1e-4 s"), message
    assert inst.machine_state() == "Initialization Mode"


@pytest.mark.parametrize("start, stop, expected", [
    (NAN, None, "invalid startTime NaN: must be finite"),
    (INF, None, "invalid startTime inf: must be finite"),
    (1.0, 0.5, "invalid stopTime 0.5: must be finite and >= startTime 1"),
    (0.0, NAN, "invalid stopTime NaN: must be finite and >= startTime 0"),
])
def test_bad_experiment_times(make3, start, stop, expected):
    inst = make3()
    assert inst.enter(start, stop) == ERROR
    assert last_error(inst) == f"fmi3EnterInitializationMode: {expected}"
    assert inst.machine_state() == "Instantiated"


# ------------------------------------------------------------- FMU states


def test_fmu_state_null_arguments(initialized3):
    inst = initialized3()
    lib = inst.lib
    assert lib.fmi3GetFMUState(inst.c, None) == ERROR
    assert last_error(inst) == "fmi3GetFMUState: FMUState is NULL while its length is 1"
    assert lib.fmi3SetFMUState(inst.c, None) == ERROR
    assert last_error(inst) == "fmi3SetFMUState: FMUState is NULL"
    assert lib.fmi3FreeFMUState(inst.c, None) == OK
    assert lib.fmi3FreeFMUState(inst.c, byref(c_void_p())) == OK
    status, state = inst.get_state()
    assert lib.fmi3SerializedFMUStateSize(inst.c, state, None) == ERROR
    assert lib.fmi3SerializedFMUStateSize(inst.c, None, byref(c_size_t())) == ERROR
    assert last_error(inst) == "fmi3SerializedFMUStateSize: FMUState is NULL"
    assert lib.fmi3DeserializeFMUState(inst.c, None, 10, byref(c_void_p())) == ERROR
    assert last_error(inst) == "fmi3DeserializeFMUState: serializedState is NULL while its length is 10"
    data = inst.serialize(state)
    buf = (c_char * len(data)).from_buffer_copy(data)
    assert lib.fmi3DeserializeFMUState(inst.c, buf, len(data), None) == ERROR
    assert lib.fmi3SerializeFMUState(inst.c, state, None, len(data)) == ERROR
    small = (c_char * 8)()
    assert lib.fmi3SerializeFMUState(inst.c, state, small, 8) == ERROR
    assert f"the buffer has 8 bytes, the state needs {len(data)}" in last_error(inst)
    assert bytes(small) == b"\0" * 8


@pytest.fixture
def serialized(initialized3):
    inst = initialized3()
    assert inst.step(0.25) == OK
    status, state = inst.get_state()
    assert status == OK
    return inst, inst.serialize(state)


def refused_state(inst, data, expected):
    before = inst.snapshot()
    status, state = inst.deserialize(data)
    assert status == ERROR and not state.value
    message = last_error(inst)
    assert message.startswith("fmi3DeserializeFMUState: invalid serialized FMU state: "), message
    assert expected in message, message
    assert inst.snapshot() == before


def test_deserialize_empty(serialized):
    inst, _ = serialized
    refused_state(inst, b"", "not a tdvass FMU state (0 bytes")


@pytest.mark.parametrize("fraction", [0.005, 0.01, 0.02, 0.1, 0.5, 0.9, 0.999])
def test_deserialize_truncated(serialized, fraction):
    inst, data = serialized
    cut = max(int(len(data) * fraction), 1)
    header, _ = fmi3.serialized_fields(data)
    expected = "without the magic" if cut < 8 else "truncated" if cut < header else "payload of"
    refused_state(inst, data[:cut], expected)


@pytest.mark.parametrize("position", [0, 7, 9, 13, 20, 53, 60, 100, 0.5, 0.75, -1])
def test_deserialize_bit_flipped(serialized, position):
    inst, data = serialized
    at = int(position * len(data)) if isinstance(position, float) else position % len(data)
    flipped = bytearray(data)
    flipped[at] ^= 0x04
    refused_state(inst, bytes(flipped), "")


@pytest.mark.parametrize("bit", range(0, 8))
def test_deserialize_every_bit_of_one_payload_byte(serialized, bit):
    inst, data = serialized
    at, length = fmi3.serialized_fields(data)
    flipped = bytearray(data)
    flipped[at + length // 3] ^= 1 << bit
    refused_state(inst, bytes(flipped), "checksum")


def test_deserialize_trailing_bytes(serialized):
    inst, data = serialized
    refused_state(inst, data + b"\0", "")


@pytest.mark.parametrize("version", [1, 2, 3, 4, 5, 8])
def test_deserialize_wrong_version(serialized, version):
    inst, data = serialized
    refused_state(inst, data[:8] + version.to_bytes(4, "little") + data[12:],
                  f"format version {version} is not supported")


def test_deserialize_other_token(serialized):
    inst, data = serialized
    other = data.replace(fmi3.instantiation_token().encode(), b"{00000000-0000-0000-0000-000000000000}")
    refused_state(inst, other, "written by the FMU with GUID {00000000-0000-0000-0000-000000000000}")


def test_a_state_of_the_fmi2_fmu_is_refused(lib, serialized):
    """Decision: both FMUs write the same format, each under its own token;
    a state serialized by the FMI 2.0 FMU is refused by the FMI 3.0 FMU
    (and the other way round), naming both tokens."""
    inst, own = serialized
    other = fmi2.Instance(lib)
    other.initialize(stop=15.0)
    assert other.step(0.25) == fmi2.OK
    status, state = other.get_state()
    data = other.serialize(state)
    assert data[:12] == own[:12]  # same magic and format version
    refused_state(inst, data, f"written by the FMU with GUID {fmi2.guid()}, this FMU has GUID "
                              f"{fmi3.instantiation_token()}")
    status, _ = other.deserialize(own)
    assert status == fmi2.ERROR
    assert f"written by the FMU with GUID {fmi3.instantiation_token()}" in other.log.last()[2]
    other.free()


def test_deserialize_checksum_valid_but_negative_mass(serialized):
    inst, data = serialized
    at, _ = fmi3.serialized_fields(data)
    # payload: phase (1), number of settings (4), then (vr u32, value u64); m_s is the second.
    m_s = at + 1 + 4 + 12 + 4
    assert int.from_bytes(data[m_s - 4 : m_s], "little") == inst.vr["m_s"]
    forged = bytearray(data)
    forged[m_s : m_s + 8] = ctypes.c_uint64.from_buffer_copy(ctypes.c_double(-1.0)).value.to_bytes(8, "little")
    refused_state(inst, fmi3.reseal(forged), "invalid value -1 for `m_s`")


def test_deserialize_checksum_valid_but_bad_structural_parameter(serialized):
    inst, data = serialized
    at, _ = fmi3.serialized_fields(data)
    count = int.from_bytes(data[at + 1 : at + 5], "little")
    forged = bytearray(data)
    for k in range(count):
        entry = at + 5 + 12 * k
        if int.from_bytes(data[entry : entry + 4], "little") == inst.vr["root_count"]:
            forged[entry + 4 : entry + 12] = (99).to_bytes(8, "little")
            break
    else:
        pytest.fail("root_count is not in the serialized settings")
    refused_state(inst, fmi3.reseal(forged), "invalid value 99 for `root_count`")


def test_set_fmu_state_of_another_instance_is_refused(initialized3):
    a = initialized3()
    b = initialized3(g=1000.0, road=2)
    assert a.step(0.5) == OK
    status, state = a.get_state()
    assert b.step(0.1) == OK
    before = b.snapshot()
    assert b.lib.fmi3SetFMUState(b.c, state) == ERROR
    assert "was not created by this instance or was already freed" in last_error(b)
    assert b.snapshot() == before
    assert b.lib.fmi3FreeFMUState(b.c, byref(state)) == ERROR
    assert state.value  # not freed, still a's
    assert a.free_state(state) == OK and not state.value


def test_double_free_of_an_fmu_state(initialized3):
    inst = initialized3()
    status, state = inst.get_state()
    copy = c_void_p(state.value)
    assert inst.free_state(state) == OK and not state.value
    assert inst.free_state(copy) == ERROR
    assert inst.lib.fmi3SetFMUState(inst.c, copy) == ERROR
    assert inst.lib.fmi3SerializedFMUStateSize(inst.c, copy, byref(c_size_t())) == ERROR


def test_a_state_restores_in_a_fresh_instance_through_serialization(initialized3):
    a = initialized3(g=2000.0, tau=0.01)
    b = initialized3()
    assert a.step(0.5) == OK
    status, state = a.get_state()
    status, moved = b.deserialize(a.serialize(state))
    assert status == OK
    assert b.lib.fmi3SetFMUState(b.c, moved) == OK
    assert b.get("g", "tau") == [2000.0, 0.01]
    for inst in (a, b):
        assert inst.step(0.5, t=0.5) == OK
    assert a.snapshot() == b.snapshot()


OUT = [name for name, (_, kind, causality, _) in fmi3.variables().items()
       if causality == "output" and kind == "Float64"]


def test_refused_calls_do_not_disturb_the_results(initialized3):
    """A run sprinkled with refused calls gives bit-identical outputs."""
    clean, noisy = initialized3(), initialized3()
    for k in range(20):
        for bad in (lambda: noisy.do_step(noisy.time + 1.0, 0.01)[0], lambda: noisy.set(m_s=1.0),
                    lambda: noisy.set(g=NAN), lambda: noisy.deserialize(b"garbage")[0],
                    lambda: noisy.lib.fmi3EnterEventMode(noisy.c), lambda: noisy.set(variant=7),
                    lambda: noisy.get_values("fmi3GetInt32", [noisy.vr["variant"]])[0]):
            assert bad() == ERROR
        assert clean.step(0.05) == OK and noisy.step(0.05) == OK
    assert clean.get(*OUT) == noisy.get(*OUT)
    assert clean.snapshot() == noisy.snapshot()


def test_unstable_gain_is_a_warning_not_an_error(make3):
    inst = make3()
    assert inst.initialize(g=-40000.0, tau=0.11) == WARNING
    assert "unstable feedback" in inst.log.last()[2]
