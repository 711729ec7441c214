"""The built FMU (target/fmu/tdvass.fmu) driven from fmpy."""

import json
import math
import subprocess
import sys
from ctypes import byref, c_double, c_int, c_void_p
from pathlib import Path

import fmpy
import fmpy.simulation
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2FMUstate
from fmpy.validation import validate_fmu

from fmu_helpers import OUTPUTS, RMS, STATES, grid

FMI2_OK, FMI2_WARNING, FMI2_DISCARD, FMI2_ERROR = 0, 1, 2, 3
FMI2_LAST_SUCCESSFUL_TIME, FMI2_TERMINATED = 2, 3

# Table 2 of the paper: RMS of BA (m/s2), SDD (m), TDD (mm).
TABLE2 = {
    1: (1.6081, 0.0312, 3.1109),  # CS
    2: (0.9715, 0.0693, 1.6606),  # PVASS
    3: (0.3068, 0.0388, 0.6251),  # TDVASS
}


def agrees_to_printed_digit(ours: float, paper: float, decimals: int = 4) -> bool:
    """Rounded to the printed precision, within one unit in the last digit."""
    unit = 10.0 ** -decimals
    return abs(round(ours, decimals) - paper) <= unit * (1 + 1e-9)


def close(a, b, rtol):
    return np.allclose(a, b, rtol=rtol, atol=0.0)


# ------------------------------------------------------------------ description


def test_validate_fmu_reports_no_problems(fmu_file):
    assert validate_fmu(str(fmu_file)) == []


def test_fmpy_info_lists_the_variables(fmu_file, model_description):
    info = subprocess.run(
        [sys.executable, "-m", "fmpy", "info", str(fmu_file)],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert "TDVASS" in info and "Co-Simulation" in info
    assert f"Variables          {len(model_description.modelVariables)}" in info
    for v in model_description.modelVariables:
        if v.causality in ("input", "output"):
            shown = v.name if len(v.name) <= 18 else "..." + v.name[-15:]
            assert shown in info, v.name
    names = {v.name for v in model_description.modelVariables}
    for extra in ["x_s_start", "v_s_start", "x_h_start", "v_h_start", "x_t_start", "v_t_start"]:
        assert extra in names
    assert model_description.guid.startswith("{") and len(model_description.guid) == 38


# ------------------------------------------------------------------ Table 2


def table2_row(fmu_file, variant):
    result = fmpy.simulate_fmu(str(fmu_file), start_values={"variant": variant}, output=RMS)
    last = result[-1]
    assert last["time"] == pytest.approx(15.0)
    return last["rms_body_acceleration"], last["rms_suspension_deflection"], 1e3 * last["rms_tire_deflection"]


def test_default_experiment_reproduces_table2_tdvass(fmu_file):
    result = fmpy.simulate_fmu(str(fmu_file), output=RMS)
    last = result[-1]
    assert last["time"] == pytest.approx(15.0)
    ours = (last["rms_body_acceleration"], last["rms_suspension_deflection"], 1e3 * last["rms_tire_deflection"])
    for value, paper in zip(ours, TABLE2[3]):
        assert agrees_to_printed_digit(value, paper), (ours, TABLE2[3])


@pytest.mark.parametrize("variant", [1, 2], ids=["CS", "PVASS"])
def test_variant_reproduces_table2_rows(fmu_file, variant):
    ours = table2_row(fmu_file, variant)
    for value, paper in zip(ours, TABLE2[variant]):
        assert agrees_to_printed_digit(value, paper), (ours, TABLE2[variant])


# ------------------------------------------------------------------ input road


def harmonic_table(t):
    t = np.asarray(t, dtype=float)
    return np.array(list(zip(t, 0.05 * np.sin(5.0 * t))), dtype=[("time", np.double), ("x_g", np.double)])


def rms_relative_errors(input_run, stop_time, fmu_file):
    reference = fmpy.simulate_fmu(str(fmu_file), output=RMS, stop_time=stop_time)[-1]
    assert input_run["time"] == pytest.approx(stop_time) and reference["time"] == pytest.approx(stop_time)
    return [abs(input_run[n] / reference[n] - 1.0) for n in RMS]


def test_input_road_with_fmpy_input_derivatives(fmu_file, monkeypatch):
    # fmpy 0.3.32 allocates room for 9 derivative values whatever the number
    # of continuous inputs, so `set_input_derivatives=True` fails with one
    # input ("Can only assign sequence of same size"). Size the buffer to
    # the inputs; fmpy itself then computes and sets the derivatives.
    original = fmpy.simulation.Input.__init__

    def sized(self, *args, **kwargs):
        original(self, *args, **kwargs)
        if getattr(self, "continuous", None):
            self.continuous = [c._replace(derivatives=(c_double * len(c.vrs))()) for c in self.continuous]

    monkeypatch.setattr(fmpy.simulation.Input, "__init__", sized)
    step, stop = 2.5e-4, 15.0
    run = fmpy.simulate_fmu(
        str(fmu_file),
        start_values={"road": 0},
        input=harmonic_table(np.arange(round(stop / step) + 1) * step),
        set_input_derivatives=True,
        output=RMS,
        output_interval=step,
        stop_time=stop,
    )[-1]
    errors = rms_relative_errors(run, stop, fmu_file)
    assert max(errors) < 1e-4, errors


def test_input_road_with_exact_piecewise_linear_slopes(make_slave):
    # Our own master: x_g and the slope of the next interpolation segment at
    # each communication point, so the FMU sees the piecewise-linear road.
    step, stop = 1e-3, 15.0
    fed = make_slave("fed").start(stop_time=stop, road=0)
    times = [k * step for k in range(round(stop / step) + 1)]
    values = [0.05 * math.sin(5.0 * t) for t in times]
    for k in range(len(times) - 1):
        fed.set(x_g=values[k])
        fed.fmu.setRealInputDerivatives([fed.vr["x_g"]], [1], [(values[k + 1] - values[k]) / step])
        fed.step_to(times[k + 1])
    harmonic = make_slave("harmonic").start(stop_time=stop)
    harmonic.step_to(stop)
    ours, reference = fed.get(RMS), harmonic.get(RMS)
    assert close(ours, reference, rtol=1e-4), (ours, reference)


def test_input_road_without_derivatives_small_step(fmu_file):
    # Zero-order hold: the RMS samples sit on the 0.1 ms internal grid. A
    # communication step incommensurate with it (the golden ratio) keeps
    # every hold interval's sampling offset uniform, so the hold error
    # averages out to second order.
    step, stop = 2e-4 * (math.sqrt(5.0) - 1.0) / 2.0, 4.0
    run = fmpy.simulate_fmu(
        str(fmu_file),
        start_values={"road": 0},
        input=harmonic_table(np.linspace(0.0, stop, 40001)),
        output=RMS,
        output_interval=step,
        stop_time=stop,
    )[-1]
    errors = rms_relative_errors(run, stop, fmu_file)
    assert max(errors) < 1e-4, errors


# ------------------------------------------------------------------ step sizes


def test_communication_steps_do_not_change_the_outputs(make_slave):
    period, n_common = 0.073, 30
    common = [j * period for j in range(n_common + 1)]
    rng = np.random.default_rng(20240601)

    def schedule(split):
        times = []
        for a, b in zip(common, common[1:]):
            times += [a + x for x in split(b - a)] + [b]
        return times

    def fixed(h):
        return lambda span: [k * h for k in range(1, round(span / h))]

    def random_cuts(span):
        cuts = np.sort(rng.uniform(0.0, span, rng.integers(0, 15)))
        return list(cuts[cuts > 1e-9])

    runs = {}
    for label, times in [
        ("1 ms", schedule(fixed(1e-3))),
        ("7.3 ms", schedule(fixed(7.3e-3))),
        ("random", schedule(random_cuts)),
    ]:
        slave = make_slave(label).start(stop_time=common[-1])
        at = {}
        for t in times:
            slave.step_to(t)
            at[t] = slave.get()
        runs[label] = np.array([at[c] for c in common[1:]])
    reference = runs["1 ms"]
    for label, outputs in runs.items():
        assert close(outputs, reference, rtol=1e-9), label


# ------------------------------------------------------------------ FMU states


def test_get_and_set_state_rolls_back(make_slave):
    slave = make_slave().start(stop_time=2.0)
    for t in grid(0.0, 0.5, 1e-3):
        slave.step_to(t)
    state = slave.fmu.getFMUstate()
    first = slave.run(grid(0.5, 1.0, 7e-3))
    slave.fmu.setFMUstate(state)
    assert slave.fmu.getRealStatus(FMI2_LAST_SUCCESSFUL_TIME) == pytest.approx(0.5)
    slave.time = 0.5
    second = slave.run(grid(0.5, 1.0, 7e-3))
    assert first == second
    # Getting into an existing state overwrites it in place.
    before = state.value
    slave.fmu.fmi2GetFMUstate(slave.fmu.component, byref(state))
    assert state.value == before
    slave.fmu.setFMUstate(state)
    slave.step_to(slave.time + 0.1)
    # Freeing sets the pointer to NULL; freeing a stale copy again is refused.
    stale = fmi2FMUstate(state.value)
    slave.fmu.freeFMUstate(state)
    assert state.value is None
    with pytest.raises(FMICallException) as e:
        slave.fmu.freeFMUstate(stale)
    assert e.value.status == FMI2_ERROR
    assert "not created by this instance or was already freed" in slave.log.last()[2]


def test_serialized_state_continues_in_a_fresh_process(make_slave, unzipdir, tmp_path):
    # A random road: its generator state must travel with the FMU state.
    slave = make_slave().start(stop_time=3.0, g=4000.0, road=2, road_seed=7)
    for t in grid(0.0, 1.0, 1e-3):
        slave.step_to(t)
    state = slave.fmu.getFMUstate()
    data = slave.fmu.serializeFMUstate(state)
    slave.fmu.freeFMUstate(state)
    assert data[:8] == b"TDVASSFS"
    here = [[v.hex() for v in row] for row in slave.run(grid(1.0, 1.5, 1e-3))]
    state_file = tmp_path / "state.bin"
    state_file.write_bytes(data)
    worker = Path(__file__).resolve().parent / "fmu_helpers.py"
    done = subprocess.run(
        [sys.executable, str(worker), "continue", str(unzipdir), str(state_file), "1.0", "1.5", "1e-3"],
        capture_output=True,
        text=True,
        check=True,
    )
    there = json.loads(done.stdout)
    assert there == here, "bit-identical continuation"


def test_corrupted_serialized_state_is_refused(make_slave):
    slave = make_slave().start(stop_time=1.0)
    slave.step_to(0.1)
    state = slave.fmu.getFMUstate()
    data = bytearray(slave.fmu.serializeFMUstate(state))
    slave.fmu.freeFMUstate(state)
    for bad in [bytes(data[:40]), bytes(data[:-1]), b"", b"not a state at all"]:
        with pytest.raises(FMICallException) as e:
            slave.fmu.deSerializeFMUstate(bad)
        assert e.value.status == FMI2_ERROR
    data[len(data) // 2] ^= 0x10
    with pytest.raises(FMICallException):
        slave.fmu.deSerializeFMUstate(bytes(data))
    assert "checksum" in slave.log.last()[2]
    slave.step_to(0.2)  # the instance is unaffected


# ------------------------------------------------------------------ life cycle


def test_reset_returns_to_the_start_values(make_slave):
    fresh = make_slave("fresh").start(stop_time=1.0).run(grid(0.0, 1.0, 0.01))
    slave = make_slave().start(stop_time=0.5, variant=1, g=100.0)
    slave.run(grid(0.0, 0.5, 0.01))
    slave.fmu.reset()
    slave.fmu.setupExperiment(startTime=0.0, stopTime=1.0)
    slave.fmu.enterInitializationMode()
    assert slave.fmu.getInteger([slave.vr["variant"]]) == [3]
    assert slave.get(["g"]) == [5386.0]
    slave.fmu.exitInitializationMode()
    slave.time = 0.0
    assert slave.run(grid(0.0, 1.0, 0.01)) == fresh


def test_two_instances_side_by_side(make_slave):
    times = grid(0.0, 1.0, 5e-3)
    alone_a = make_slave("alone_a").start(stop_time=1.0).run(times)
    alone_b = make_slave("alone_b").start(stop_time=1.0, variant=1, road=1).run(times)
    a = make_slave("a").start(stop_time=1.0)
    b = make_slave("b").start(stop_time=1.0, variant=1)
    both_a, both_b = [], []
    for t in times:
        a.step_to(t)
        b.step_to(t)
        both_a.append(a.get())
        both_b.append(b.get())
    assert both_a == alone_a and both_b == alone_b
    assert both_a != both_b


def test_guid_mismatch_is_refused(make_slave):
    with pytest.raises(Exception, match="Failed to instantiate"):
        make_slave(guid="{00000000-0000-0000-0000-000000000000}")


def test_guid_mismatch_is_logged(unzipdir, model_description):
    from fmpy.fmi2 import FMU2Slave

    from fmu_helpers import LogCapture

    log = LogCapture()
    fmu = FMU2Slave(
        guid="{00000000-0000-0000-0000-000000000000}",
        unzipDirectory=str(unzipdir),
        modelIdentifier="tdvass",
        instanceName="wrong",
    )
    with pytest.raises(Exception, match="Failed to instantiate"):
        fmu.instantiate(callbacks=log.callbacks)
    status, category, message = log.last()
    assert status == FMI2_ERROR and category == "logStatusError"
    assert "GUID {00000000-0000-0000-0000-000000000000} does not match" in message
    assert model_description.guid in message
    fmu.freeLibrary()


def test_call_in_wrong_state_is_refused(make_slave):
    slave = make_slave()
    with pytest.raises(FMICallException) as e:
        slave.fmu.fmi2DoStep(slave.fmu.component, 0.0, 0.1, 1)
    assert e.value.status == FMI2_ERROR
    assert slave.log.last() == (FMI2_ERROR, "logStatusError", "fmi2DoStep: not allowed in state instantiated")
    # Refused calls change nothing: the instance goes on normally.
    slave.start(stop_time=1.0)
    slave.step_to(0.1)
    with pytest.raises(FMICallException) as e:
        slave.fmu.exitInitializationMode()
    assert slave.log.last()[2] == "fmi2ExitInitializationMode: not allowed in state stepComplete"


# ------------------------------------------------------------------ values


def test_bad_values_are_refused_naming_variable_and_value(make_slave):
    slave = make_slave()
    for name, value, shown in [("m_s", -1.0, "-1"), ("tau", -0.5, "-0.5"), ("g", math.nan, "NaN"),
                               ("max_internal_step", -1e-4, "-0.0001"), ("w_ba", math.inf, "inf")]:
        with pytest.raises(FMICallException) as e:
            slave.set(**{name: value})
        assert e.value.status == FMI2_ERROR
        message = slave.log.last()[2]
        assert f"`{name}`" in message and shown in message, message
    with pytest.raises(FMICallException):
        slave.set(road_class=9)
    assert "road_class" in slave.log.last()[2] and "9" in slave.log.last()[2]
    slave.start(stop_time=1.0)
    with pytest.raises(FMICallException):
        slave.set(m_s=300.0)
    assert "fixed parameter" in slave.log.last()[2]
    with pytest.raises(FMICallException):
        slave.set(x_s=1.0)
    assert "output" in slave.log.last()[2]
    slave.set(g=5000.0, w_ba=1.0)  # tunable between steps
    slave.step_to(0.1)
    assert slave.get(["g"]) == [5000.0]


def test_tunable_gain_acts_between_steps(make_slave):
    tuned = make_slave("tuned").start(stop_time=1.0)
    tuned.step_to(0.5)
    tuned.set(g=0.0)
    tuned.step_to(1.0)
    assert tuned.get(["control_force"]) == [0.0]
    untuned = make_slave("untuned").start(stop_time=1.0)
    untuned.step_to(1.0)
    assert untuned.get(["x_s"]) != tuned.get(["x_s"])


def test_divergence_is_discarded_with_last_successful_time(fmu_file):
    result = fmpy.simulate_fmu(
        str(fmu_file),
        start_values={"g": -40000.0, "tau": 0.11, "x_s_start": 0.01},
        output=OUTPUTS,
    )
    end = result[-1]["time"]
    assert 1.0 < end < 15.0, end
    for name in OUTPUTS:
        assert np.all(np.isfinite(result[name])), name
    assert abs(result[-1]["x_t"]) > 100.0


def test_stability_verification_points(make_slave):
    # Section 3.3: A1* .. A6*.
    points = [(40000.0, 0.03, True), (-40000.0, 0.11, False), (40000.0, 0.15, False),
              (-40000.0, 0.25, True), (40000.0, 0.3, True), (-40000.0, 0.4, False)]
    for g, tau, stable in points:
        slave = make_slave(f"A_{g}_{tau}")
        slave.fmu.setupExperiment(startTime=0.0)
        slave.set(g=g, tau=tau, x_s_start=0.01)
        slave.fmu.enterInitializationMode()
        assert slave.fmu.getBoolean([slave.vr["stable"]]) == [stable], (g, tau)
        (abscissa,) = slave.get(["spectral_abscissa"])
        assert (abscissa < 0) == stable
        if not stable:
            slave.fmu.exitInitializationMode()  # fmi2Warning, not an exception
            assert any(s == FMI2_WARNING and f"g = {g:g}" in m for s, _, m in slave.log.messages)


# ------------------------------------------------------------------ derivatives


def test_directional_and_output_derivatives(make_slave):
    slave = make_slave().start(stop_time=1.0)
    slave.step_to(0.3)
    x = slave.get(STATES)
    (ba,) = slave.get(["body_acceleration"])
    states = [slave.vr[n] for n in STATES]
    (linear,) = slave.fmu.getDirectionalDerivative([slave.vr["body_acceleration"]], states, x)
    assert linear == pytest.approx(ba, rel=1e-12)
    dx = slave.fmu.getRealOutputDerivatives([slave.vr["x_s"], slave.vr["x_t"]], [1, 1])
    assert dx == [x[1], x[5]]
    (dba,) = slave.fmu.getRealOutputDerivatives([slave.vr["body_acceleration"]], [1])
    h = 1e-5
    slave.step_to(0.3 + h)
    (ba_next,) = slave.get(["body_acceleration"])
    assert (ba_next - ba) / h == pytest.approx(dba, rel=1e-3)
    with pytest.raises(FMICallException):
        slave.fmu.getRealOutputDerivatives([slave.vr["x_s"]], [2])


# ------------------------------------------------------------------ instantiation


def test_instantiate_refusals_and_resource_locations(unzipdir, model_description):
    from fmpy.fmi2 import FMU2Slave

    from fmu_helpers import LogCapture

    log = LogCapture()
    fmu = FMU2Slave(guid=model_description.guid, unzipDirectory=str(unzipdir), modelIdentifier="tdvass")
    guid = model_description.guid.encode()
    here = (Path(unzipdir) / "resources").as_uri().encode()

    def instantiate(name=b"i", kind=1, resource=here, guid=guid, callbacks=log.callbacks):
        return fmu.fmi2Instantiate(name, kind, guid, resource, byref(callbacks) if callbacks else None, 0, 0)

    refused = [
        (dict(kind=7), "unknown fmuType 7"),
        (dict(name=b""), "instanceName is empty"),
        (dict(name=None), "instanceName is NULL"),
        (dict(guid=b"{x}"), "GUID {x} does not match"),
        (dict(resource=b"http://host/resources"), "unsupported scheme"),
        (dict(resource=b"file://server/share"), "unsupported host"),
        # printf conversions in a logged value are harmless: every % is doubled.
        (dict(resource=b"file:///tmp/%zz%s%n%d"), "file:///tmp/%zz%s%n%d"),
    ]
    for arguments, expected in refused:
        assert instantiate(**arguments) is None, arguments
        status, category, message = log.last()
        assert status == FMI2_ERROR and category == "logStatusError"
        assert message.startswith("fmi2Instantiate: ") and expected in message, message
    assert instantiate(callbacks=None) is None  # no callbacks: refused silently

    for resource in [here, b"file:" + here[len(b"file://"):], b"file://localhost" + here[len(b"file://"):],
                     b"file:///tmp/with%20space", None]:
        component = instantiate(resource=resource)
        assert component is not None, resource
        fmu.fmi2FreeInstance(component)

    # fmi2ModelExchange makes an instance; a Model Exchange function on a
    # Co-Simulation instance is refused by the state table.
    component = instantiate(kind=0)
    assert component is not None
    fmu.fmi2FreeInstance(component)
    component = instantiate()
    set_time = fmu.dll.fmi2SetTime
    set_time.argtypes, set_time.restype = [c_void_p, c_double], c_int
    assert set_time(component, 0.0) == FMI2_ERROR
    assert log.last()[2] == "fmi2SetTime: not allowed in state instantiated"
    fmu.fmi2FreeInstance(component)
    fmu.freeLibrary()
