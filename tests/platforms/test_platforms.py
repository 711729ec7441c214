"""The same harness (harness.c) on every platform: linux64 natively, win64
under wine, aarch64 under qemu. Every output at every communication point
must agree with the native linux64 run to 1e-12 relative; the largest
difference seen is printed at the end of the run (bit-identical expected)."""

import math

import pytest
from conftest import OBSERVED, RELATIVE_TOLERANCE

OK, ERROR = 0, 3  # fmi2Status

OTHER_PLATFORMS = ["win64", "aarch64"]
ALL_PLATFORMS = ["linux64", *OTHER_PLATFORMS]
SAVE_AT = 5.0  # s, where harness.c saves the state


def relative_difference(a: float, b: float) -> float:
    if a == b:
        return 0.0
    if math.isnan(a) or math.isnan(b):
        return math.inf
    return abs(a - b) / max(abs(a), abs(b))


def compare(platform: str, file: str, expected: tuple, actual: tuple) -> None:
    """Same header, same times, every value within the tolerance; records
    the largest relative difference."""
    (expected_header, expected_rows), (header, rows) = expected, actual
    assert header == expected_header
    assert len(rows) == len(expected_rows), f"{file}: {len(rows)} rows, expected {len(expected_rows)}"
    largest, where = 0.0, None
    for row, expected_row in zip(rows, expected_rows):
        assert row[0] == expected_row[0], f"{file}: time {row[0]} instead of {expected_row[0]}"
        for column, (value, expected_value) in enumerate(zip(row, expected_row)):
            assert math.isfinite(value), f"{file}: {header[column]} = {value} at t = {row[0]}"
            difference = relative_difference(value, expected_value)
            if difference > largest:
                largest, where = difference, (row[0], header[column], value, expected_value)
    count = len(rows) * len(header)
    OBSERVED.setdefault(platform, {})[file] = [largest, count]
    assert largest <= RELATIVE_TOLERANCE, (
        f"{file}: relative difference {largest:.3g} at t = {where[0]} s, value reference {where[1]}: "
        f"{where[2]!r} vs linux64 {where[3]!r}")


def after_save(table: tuple) -> tuple:
    header, rows = table
    return header, [row for row in rows if row[0] > SAVE_AT + 1e-9]


@pytest.mark.parametrize("platform", OTHER_PLATFORMS)
@pytest.mark.parametrize("file", ["default.csv", "iso_c_cs.csv"])
def test_experiments_agree_with_linux64(results, platform, file):
    linux64, other = results("linux64"), results(platform)
    compare(platform, file, linux64.table(file), other.table(file))


def test_experiments_cover_the_default_experiment_and_differ_from_each_other(results):
    """The comparisons above are not between empty or constant tables."""
    header, default = results("linux64").table("default.csv")
    _, iso = results("linux64").table("iso_c_cs.csv")
    assert len(default) == len(iso) == 15001
    assert default[0][0] == 0.0 and default[-1][0] == pytest.approx(15.0, abs=1e-12)
    x_s = header.index("31")
    assert max(abs(row[x_s]) for row in default) > 1e-3  # the body moves on the harmonic road
    assert [row[x_s] for row in default] != [row[x_s] for row in iso]


@pytest.mark.parametrize("platform", ALL_PLATFORMS)
def test_serialize_free_deserialize_continues_the_run(results, platform):
    """The run continued in a new instance from the serialized state at 5 s
    is the uninterrupted default experiment of the same platform."""
    run = results(platform)
    continued = run.table("roundtrip.csv")
    assert continued[1] and continued[1][0][0] == pytest.approx(SAVE_AT + 1e-3)
    compare(platform, "roundtrip.csv", after_save(results("linux64").table("default.csv")), continued)
    compare(platform, "roundtrip/own", after_save(run.table("default.csv")), continued)


@pytest.mark.parametrize("platform", ALL_PLATFORMS)
def test_state_written_on_linux64_restores(results, platform):
    """The bytes that the linux64 library serialized restore on every
    platform and continue the run as linux64 does."""
    restored = results(platform).table("restored.csv")
    compare(platform, "restored.csv", after_save(results("linux64").table("default.csv")), restored)


@pytest.mark.parametrize("platform", OTHER_PLATFORMS)
def test_serialized_state_is_the_same_bytes_on_every_platform(results, platform):
    linux64 = results("linux64").state()
    assert len(linux64) > 100
    assert results(platform).state() == linux64


# The documented outcome of each bad call (tests/robustness/test_bad_input.py):
# status (or NULL for a refused fmi2Instantiate) and a part of the message
# logged for it ("" where there is no instance to log through).
BAD_INPUT = {
    "null_instance_do_step": (ERROR, ""),
    "null_instance_get_real": (ERROR, ""),
    "wrong_guid": ("NULL", "fmi2Instantiate: GUID {00000000-0000-0000-0000-000000000000} does not match"),
    "model_exchange": ("instance", ""),
    "unknown_fmu_type": ("NULL", "fmi2Instantiate: unknown fmuType 7"),
    "do_step_before_initialization": (ERROR, "fmi2DoStep: not allowed in state instantiated"),
    "unknown_value_reference_get": (ERROR, "fmi2GetReal: unknown value reference 9999 (for a Real)"),
    "unknown_value_reference_set": (ERROR, "fmi2SetReal: unknown value reference 9999 (for a Real)"),
    "nan_parameter": (ERROR, "fmi2SetReal: invalid value NaN for `g`: must be finite"),
    "negative_tau": (ERROR, "fmi2SetReal: invalid value -0.0002 for `tau`: must be >= 0"),
    "set_output": (ERROR, "fmi2SetReal: `x_s` is an output and cannot be set"),
    "delay_too_long_at_initialization": (ERROR, "the delay needs more than 8388608 history nodes"),
    "negative_step_size": (ERROR, "fmi2DoStep: invalid communicationStepSize -0.001: must be finite and > 0"),
    "null_state_pointer": (ERROR, "fmi2GetFMUstate: FMUstate is NULL"),
    "truncated_state": (ERROR, "fmi2DeSerializeFMUstate: invalid serialized FMU state: payload of"),
    "bit_flipped_state": (ERROR, "fmi2DeSerializeFMUstate: invalid serialized FMU state: checksum mismatch"),
    "serialize_buffer_too_small": (ERROR, "fmi2SerializeFMUstate: the buffer has 8 bytes, the state needs"),
    "simulates_after_refusals": (OK, ""),
    # Model Exchange (the exact messages: tests/robustness/test_model_exchange_bad_input.py).
    "me_get_derivatives_before_initialization": (ERROR, "fmi2GetDerivatives: not allowed in state instantiated"),
    "me_set_continuous_states_in_event_mode": (ERROR, "fmi2SetContinuousStates: not allowed in state eventMode"),
    "me_null_event_info": (ERROR, "fmi2NewDiscreteStates: eventInfo is NULL"),
    "me_do_step": (ERROR, "fmi2DoStep: not allowed in state continuousTimeMode"),
    "me_too_few_states": (ERROR, "19 continuous states given, the model has 20"),
    "me_too_many_derivatives": (ERROR, "fmi2GetDerivatives: 21 derivatives asked for, the model has 20"),
    "me_nan_state": (ERROR, "continuous state 3 (`v_h`) = NaN is not finite"),
    "me_time_before_completed_step": (ERROR, "time 0.0005 s is before 0.001 s, the last completed integrator step "
                                             "or event"),
    "me_null_flags": (ERROR, "fmi2CompletedIntegratorStep: enterEventMode is NULL"),
    "me_state_into_cs_instance": (ERROR, "fmi2DeSerializeFMUstate: a Model Exchange state cannot be restored into a "
                                         "Co-Simulation instance"),
    "me_integrates_after_refusals": (OK, ""),
}


@pytest.mark.parametrize("platform", ALL_PLATFORMS)
def test_bad_input_is_refused_with_the_documented_status(results, platform):
    observed = results(platform).bad_input()
    assert set(observed) == set(BAD_INPUT)
    wrong = {case: observed[case] for case, (result, message) in BAD_INPUT.items()
             if observed[case][0] != str(result) or message not in observed[case][1]
             or (not message and observed[case][1])}
    assert not wrong, f"{platform}: {wrong}"


@pytest.mark.parametrize("platform", OTHER_PLATFORMS)
def test_bad_input_messages_are_the_same_as_on_linux64(results, platform):
    assert results(platform).bad_input() == results("linux64").bad_input()


# ------------------------------------------------------------ Model Exchange

ME_ROWS = 1001  # harness.c: 1 s of Euler steps of 0.1 ms, a row every 1 ms (and t = 0)


@pytest.mark.parametrize("platform", OTHER_PLATFORMS)
def test_model_exchange_run_agrees_with_linux64(results, platform):
    """States, derivatives, event indicator and outputs of the Model
    Exchange run (a master's Euler integration) are the same bits
    everywhere."""
    compare(platform, "model_exchange.csv", results("linux64").table("model_exchange.csv"),
            results(platform).table("model_exchange.csv"))


def test_model_exchange_run_follows_the_co_simulation(results):
    """The Euler run through Model Exchange tracks the co-simulation of the
    same experiment (the FMU's own solver): the body displacement x_s within
    1 % of its range over the first second, row by row (same 1 ms grid)."""
    header, rows = results("linux64").table("model_exchange.csv")
    cs_header, cs_rows = results("linux64").table("default.csv")
    assert len(rows) == ME_ROWS
    assert header[1:21] == [f"x{i}" for i in range(20)] and header[41] == "z0"
    x_s, cs_x_s = header.index("31"), cs_header.index("31")
    assert [row[x_s] for row in rows] == [row[1] for row in rows]  # x_s is the first state
    me = [row[x_s] for row in rows]
    cs = [row[cs_x_s] for row in cs_rows[:ME_ROWS]]
    scale = max(abs(v) for v in cs)
    assert scale > 1e-3
    worst = max(abs(a - b) for a, b in zip(me, cs))
    assert worst <= 0.01 * scale, f"largest difference {worst} m of a range of {scale} m"
    assert all(row[41] > 0 for row in rows)  # the tire keeps contact on the default road
