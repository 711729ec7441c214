"""Model Exchange: both FMUs driven by fmpy's own solvers (CVODE, Euler)
against the exact co-simulation, the delay history under every habit of
calling CompletedIntegratorStep, FMU states in the middle of a run, and
the unilateral tire's events."""

from __future__ import annotations

import fmpy
import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from fmu_helpers import fmu_path
from test_fmu import TABLE2, agrees_to_printed_digit

# The time averages compared (the tire-load ratio is k_t RMS(TDD) / W).
AVERAGES = [
    "rms_body_acceleration",
    "rms_suspension_deflection",
    "rms_tire_deflection",
    "objective",
    "rms_weighted_body_acceleration",
    "rms_dynamic_tire_load_ratio",
]

FMUS = {"fmi2": fmu_path(), "fmi3": fmu_path().with_name("tdvass-fmi3.fmu")}

ISO = {"road": 2, "vehicle_speed": 20.0}

# A random road is linear between nodes 1 ms apart; at each kink CVODE
# restarts at low order, so it needs more steps than fmpy's default limit
# of 500 per output interval allows at longer intervals (docs/fmu.md).
RANDOM_ROAD_INTERVAL = 1e-3

# (name, start values, duration): the three variants, the harmonic road up
# to 60 rad/s, ISO C and D, the paper road; tau = 0, 2e-4 (far below the
# solver's steps) and 0.011; g of both signs.
CASES = [
    ("cs-harmonic", {"variant": 1}, 3.0),
    ("pvass-harmonic", {"variant": 2}, 3.0),
    ("tdvass-harmonic", {"variant": 3, "tau": 0.011}, 3.0),
    ("tdvass-tau0", {"variant": 3, "tau": 0.0}, 3.0),
    ("tdvass-tau2e-4", {"variant": 3, "tau": 2e-4}, 3.0),
    ("tdvass-negative-g", {"variant": 3, "tau": 0.011, "g": -2000.0}, 3.0),
    ("tdvass-60rad", {"variant": 3, "tau": 0.011, "road_angular_frequency": 60.0, "road_amplitude": 0.005}, 1.0),
    ("tdvass-iso-c", {"variant": 3, "road_class": 3, **ISO}, 1.0),
    ("cs-iso-d", {"variant": 1, "road_class": 4, **ISO}, 1.0),
    ("tdvass-paper-road", {"variant": 3, "road": 3}, 2.0),
]


def last_row(result):
    return {name: result[name][-1] for name in result.dtype.names}


def run(fmu, fmi_type, start_values, duration, **options):
    result = fmpy.simulate_fmu(
        str(fmu),
        fmi_type=fmi_type,
        start_values=start_values,
        stop_time=duration,
        output=AVERAGES + ["lift_off_count"],
        **options,
    )
    return last_row(result)


def cvode(fmu, start_values, duration, **options):
    interval = RANDOM_ROAD_INTERVAL if start_values.get("road") == 2 else 0.01
    return run(
        fmu,
        "ModelExchange",
        start_values,
        duration,
        solver="CVode",
        relative_tolerance=1e-8,
        output_interval=interval,
        **options,
    )


@pytest.mark.parametrize("version", FMUS)
def test_both_interfaces_are_declared_and_valid(version):
    md = read_model_description(str(FMUS[version]))
    assert md.modelExchange.modelIdentifier == "tdvass"
    assert md.coSimulation.modelIdentifier == "tdvass"
    assert md.numberOfContinuousStates == 20
    assert md.numberOfEventIndicators == 1
    assert validate_fmu(str(FMUS[version])) == []


@pytest.mark.parametrize("version", FMUS)
@pytest.mark.parametrize("name, start_values, duration", CASES, ids=[c[0] for c in CASES])
def test_cvode_agrees_with_the_exact_cosimulation(version, name, start_values, duration):
    me = cvode(FMUS[version], start_values, duration)
    cs = run(FMUS[version], "CoSimulation", start_values, duration)
    for key in AVERAGES:
        assert me[key] == pytest.approx(cs[key], rel=1e-5, abs=0.0), (key, me[key], cs[key])


@pytest.mark.parametrize("version", FMUS)
@pytest.mark.parametrize("variant", [1, 2, 3])
def test_table2_through_model_exchange(version, variant):
    me = cvode(FMUS[version], {"variant": variant}, 15.0)
    ours = (me["rms_body_acceleration"], me["rms_suspension_deflection"], 1e3 * me["rms_tire_deflection"])
    for value, paper in zip(ours, TABLE2[variant]):
        assert agrees_to_printed_digit(value, paper), (ours, TABLE2[variant])


def test_euler_converges_to_the_cosimulation():
    start = {"variant": 3, "tau": 0.011}
    cs = run(FMUS["fmi2"], "CoSimulation", start, 1.0)
    errors = []
    # fmpy's Euler steps by the output interval.
    for step in (1e-4, 5e-5):
        me = run(
            FMUS["fmi2"], "ModelExchange", start, 1.0, solver="Euler", step_size=step, output_interval=step
        )
        errors.append(abs(me["rms_body_acceleration"] / cs["rms_body_acceleration"] - 1))
    # First order: halving the step halves the error.
    assert errors[1] < 0.6 * errors[0], errors
    assert errors[1] < 1e-2, errors


@pytest.mark.parametrize("version", FMUS)
def test_lift_offs_agree_with_the_cosimulations_located_switches(version):
    DURATION = 1.5
    start = {"variant": 3, "tau": 0.011, "road_class": 4, "tire_contact": 1, **ISO}
    md = read_model_description(str(FMUS[version]))
    me = fmpy.simulate_fmu(
        str(FMUS[version]),
        fmi_type="ModelExchange",
        start_values=start,
        stop_time=DURATION,
        solver="CVode",
        relative_tolerance=1e-8,
        output_interval=RANDOM_ROAD_INTERVAL,
        record_events=True,
        output=["lift_off_count"],
    )
    counts = me["lift_off_count"]
    me_times = me["time"][1:][np.diff(counts) > 0]
    cs_times = cosimulation_lift_offs(FMUS[version], md, start, DURATION)
    assert len(cs_times) > 5
    assert len(me_times) == len(cs_times), (me_times, cs_times)
    assert np.max(np.abs(me_times - cs_times)) < 1e-6, (me_times, cs_times)
    cs = run(FMUS[version], "CoSimulation", start, DURATION)
    assert counts[-1] == cs["lift_off_count"]


def cosimulation_lift_offs(fmu, md, start, duration):
    """The lift-off times the co-simulation logs (its located switches)."""
    times = []

    def logger(*arguments):
        # FMI 2.0: (component, instance, status, category, message);
        # FMI 3.0: (environment, status, category, message).
        text = arguments[-1].decode()
        if "lift-off at t = " in text:
            times.append(float(text.split("lift-off at t = ")[1].split(" ")[0]))

    fmpy.simulate_fmu(
        str(fmu),
        fmi_type="CoSimulation",
        start_values=start,
        stop_time=duration,
        debug_logging=True,
        logger=logger,
        output=["lift_off_count"],
    )
    return np.array(times)


# ------------------------------------------------- the delay history's habits


class RungeKutta:
    """A master of its own: the FMI 2.0 Model Exchange FMU integrated by the
    classical Runge–Kutta method at a fixed step, calling
    fmi2CompletedIntegratorStep at every step, every `every` steps, or never,
    and optionally evaluating the derivatives once past each step end before
    stepping back (as fmpy's CVODE loop does)."""

    def __init__(self, unzipdir, md, start_values, name="rk4"):
        from ctypes import c_double
        from fmpy.fmi2 import FMU2Model

        self.md = md
        self.fmu = FMU2Model(
            guid=md.guid,
            unzipDirectory=unzipdir,
            modelIdentifier=md.modelExchange.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        by_name = {v.name: v for v in md.modelVariables}
        for key, value in start_values.items():
            v = by_name[key]
            if v.type == "Real":
                self.fmu.setReal([v.valueReference], [float(value)])
            else:
                self.fmu.setInteger([v.valueReference], [int(value)])
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.fmu.newDiscreteStates()
        self.fmu.enterContinuousTimeMode()
        self.n = md.numberOfContinuousStates
        self.buffer = (c_double * self.n)()
        self.fmu.getContinuousStates(self.buffer, self.n)
        self.x = np.array(self.buffer[:])
        self.t = 0.0
        self.by_name = by_name

    def rhs(self, t, x):
        from ctypes import c_double

        self.fmu.setTime(t)
        self.fmu.setContinuousStates((c_double * self.n)(*x), self.n)
        self.fmu.getDerivatives(self.buffer, self.n)
        return np.array(self.buffer[:])

    def run(self, t_end, h, every=1, peek=False):
        from ctypes import c_double

        steps = int(round((t_end - self.t) / h))
        start = self.t
        for i in range(1, steps + 1):
            t, x = self.t, self.x
            k1 = self.rhs(t, x)
            k2 = self.rhs(t + h / 2, x + h / 2 * k1)
            k3 = self.rhs(t + h / 2, x + h / 2 * k2)
            k4 = self.rhs(t + h, x + h * k3)
            self.x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            self.t = start + i * h
            if peek:
                self.rhs(self.t + 0.5 * h, self.x)
            self.fmu.setTime(self.t)
            self.fmu.setContinuousStates((c_double * self.n)(*self.x), self.n)
            if every and i % every == 0:
                self.fmu.completedIntegratorStep()
        return self.x

    def read(self, name):
        return self.fmu.getReal([self.by_name[name].valueReference])[0]

    def free(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


@pytest.fixture(scope="module")
def me_unzipdir(tmp_path_factory):
    return fmpy.extract(str(FMUS["fmi2"]), unzipdir=str(tmp_path_factory.mktemp("me")))


@pytest.mark.parametrize("tau", [0.011, 2e-4])
def test_every_completion_habit_agrees_with_the_cosimulation(me_unzipdir, tau):
    """Completing every step keeps RK4's order (test_model_exchange_masters.py);
    completing every output interval or never, with or without an evaluation
    past each step end, still agrees with the exact co-simulation."""
    md = read_model_description(str(FMUS["fmi2"]))
    start = {"variant": 3, "tau": tau}
    finals = {}
    for habit, every, peek in [
        ("every step", 1, False),
        ("every output interval", 50, True),
        ("never", 0, True),
        ("never, no peek", 0, False),
    ]:
        master = RungeKutta(me_unzipdir, md, start, name=habit)
        master.run(0.5, 2e-4, every=every, peek=peek)
        finals[habit] = master.read("rms_body_acceleration")
        master.free()
    cs = run(FMUS["fmi2"], "CoSimulation", start, 0.5)["rms_body_acceleration"]
    for habit, value in finals.items():
        assert value == pytest.approx(cs, rel=1e-6, abs=0.0), (habit, finals, cs)
    # Completing every step is the most accurate habit.
    errors = {habit: abs(value / cs - 1) for habit, value in finals.items()}
    assert errors["every step"] <= min(errors.values()), errors


def test_an_fmu_state_taken_mid_run_replays_exactly(me_unzipdir):
    md = read_model_description(str(FMUS["fmi2"]))
    master = RungeKutta(me_unzipdir, md, {"variant": 3, "tau": 0.011})
    master.run(0.25, 2e-4, every=0)
    state = master.fmu.getFMUstate()
    serialized = master.fmu.serializeFMUstate(state)
    t, x = master.t, master.x.copy()
    first = master.run(0.5, 2e-4, every=0).copy()
    master.fmu.setFMUstate(state)
    master.t, master.x = t, x.copy()
    second = master.run(0.5, 2e-4, every=0).copy()
    assert np.array_equal(first, second)
    master.fmu.deSerializeFMUstate(serialized, state)
    master.fmu.setFMUstate(state)
    master.t, master.x = t, x.copy()
    third = master.run(0.5, 2e-4, every=0).copy()
    assert np.array_equal(first, third)
    master.fmu.freeFMUstate(state)
    master.free()
