"""The chassis FMUs (target/fmu/tdvass-chassis.fmu, FMI 2.0, and
tdvass-chassis-fmi3.fmu, FMI 3.0; both Co-Simulation and Model Exchange; here in Co-Simulation) driven from
fmpy: their descriptions and dependencies, the rigid body's motion in
closed form under a held force and (FMI 2.0) under a ramped one, the
immediate feedthrough of the forces to the accelerations, the decoupling
pitch inertia, the independence of the result from the communication
grid, FMU states and refused values."""

import re
import zipfile

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from fmu_helpers import Slave

FMI2_ERROR = FMI3_ERROR = 3
FMI2_WARNING = 1
NAN, INF = float("nan"), float("inf")

FORCES = ["force_fl", "force_fr", "force_rl", "force_rr"]
CORNERS = ["fl", "fr", "rl", "rr"]
ATTACHMENT = [f"displacement_{c}" for c in CORNERS] + [f"velocity_{c}" for c in CORNERS]
POSITIONS = ["heave", "pitch", "roll"]
RATES = ["heave_velocity", "pitch_rate", "roll_rate"]
ACCELERATIONS = ["heave_acceleration", "pitch_acceleration", "roll_acceleration"]
FEEDTHROUGH = ACCELERATIONS + ["seat_acceleration"]
GEOMETRY = ["mass", "a", "b", "track_front", "track_rear", "pitch_inertia", "roll_inertia", "seat_x", "seat_y"]

# A chassis other than the default: centre of gravity nearer the front,
# unequal tracks, pitch inertia away from m a b.
OTHER = {"mass": 1530.0, "a": 1.12, "b": 1.58, "track_front": 1.56, "track_rear": 1.49,
         "pitch_inertia": 2710.0, "roll_inertia": 515.0, "seat_x": -0.2, "seat_y": 0.41}


class Chassis:
    """One Co-Simulation instance of a chassis FMU, FMI 2.0 or 3.0, with
    name-based access to its Float64 variables and its log, (status,
    category, message)."""

    def __init__(self, unzipdir, md, name="chassis"):
        self.md = md
        self.fmi3 = md.fmiVersion == "3.0"
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.time = 0.0
        if self.fmi3:
            self._messages = []
            self.fmu = FMU3Slave(guid=md.guid, unzipDirectory=unzipdir,
                                 modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
            self.fmu.instantiate(logMessage=self._log)
        else:
            self._slave = Slave(unzipdir, md, name=name)
            self.fmu = self._slave.fmu

    def _log(self, _environment, status, category, message):
        self._messages.append((status, (category or b"").decode(), (message or b"").decode(errors="replace")))

    @property
    def messages(self):
        return self._messages if self.fmi3 else self._slave.log.messages

    def last(self):
        return self.messages[-1]

    def enter(self, stop_time=1.0):
        if self.fmi3:
            self.fmu.enterInitializationMode(startTime=0.0, stopTime=stop_time)
        else:
            self.fmu.setupExperiment(startTime=0.0, stopTime=stop_time)
            self.fmu.enterInitializationMode()

    def exit(self):
        self.fmu.exitInitializationMode()

    def start(self, stop_time=1.0, **values):
        """Parameters and forces set before initialization (FMI 2.0: after
        fmi2SetupExperiment), initialized at t = 0."""
        if self.fmi3:
            self.set(**values)
            self.enter(stop_time)
        else:
            self.enter(stop_time)
            self.set(**values)
        self.exit()
        self.time = 0.0
        return self

    def set(self, **values):
        for name, value in values.items():
            (self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal)([self.vr[name]], [float(value)])

    def get(self, *names) -> list[float]:
        vrs = [self.vr[n] for n in names]
        return list(self.fmu.getFloat64(vrs) if self.fmi3 else self.fmu.getReal(vrs))

    def ramp(self, **rates):
        """FMI 2.0: order-1 input derivatives of the forces."""
        names = list(rates)
        return self.fmu.setRealInputDerivatives([self.vr[n] for n in names], [1] * len(names),
                                                [float(rates[n]) for n in names])

    def step(self, h):
        self.fmu.doStep(self.time, h)
        self.time += h

    def get_state(self):
        return self.fmu.getFMUState() if self.fmi3 else self.fmu.getFMUstate()

    def set_state(self, state):
        (self.fmu.setFMUState if self.fmi3 else self.fmu.setFMUstate)(state)

    def free_state(self, state):
        (self.fmu.freeFMUState if self.fmi3 else self.fmu.freeFMUstate)(state)

    def serialize(self, state) -> bytes:
        return bytes(self.fmu.serializeFMUState(state) if self.fmi3 else self.fmu.serializeFMUstate(state))

    def deserialize(self, data: bytes):
        return self.fmu.deserializeFMUState(data) if self.fmi3 else self.fmu.deSerializeFMUstate(data)

    def free(self):
        if self.fmu is not None:
            self.fmu.freeInstance()
            self.fmu = None


@pytest.fixture(scope="module", params=["2.0", "3.0"], ids=["fmi2", "fmi3"])
def chassis_fmu(request, chassis_file, chassis_fmi3_file, tmp_path_factory):
    """(path, model description, unzip directory) of one chassis FMU."""
    path = chassis_file if request.param == "2.0" else chassis_fmi3_file
    md = read_model_description(str(path))
    assert md.fmiVersion == request.param
    return path, md, extract(str(path), unzipdir=str(tmp_path_factory.mktemp("chassis")))


@pytest.fixture
def make_chassis(chassis_fmu):
    """Factory of chassis instances, all freed at the end of the test."""
    _, md, unzipdir = chassis_fmu
    made = []

    def make(name="chassis"):
        chassis = Chassis(unzipdir, md, name=name)
        made.append(chassis)
        return chassis

    yield make
    for chassis in made:
        chassis.free()


def defaults(md) -> dict:
    """The parameters' start values."""
    return {v.name: float(v.start) for v in md.modelVariables if v.name in GEOMETRY}


def corner_positions(p) -> dict:
    """Each corner's attachment point (x ahead, y left of the centre of gravity)."""
    return {"fl": (p["a"], p["track_front"] / 2), "fr": (p["a"], -p["track_front"] / 2),
            "rl": (-p["b"], p["track_rear"] / 2), "rr": (-p["b"], -p["track_rear"] / 2)}


def accelerations(p, forces) -> list[float]:
    """[z'', θ'', φ''] of the corners' forces {corner: N}."""
    where = corner_positions(p)
    return [sum(forces.values()) / p["mass"],
            sum(where[c][0] * f for c, f in forces.items()) / p["pitch_inertia"],
            sum(where[c][1] * f for c, f in forces.items()) / p["roll_inertia"]]


def close(got, expected, rel):
    return abs(got - expected) <= rel * abs(expected)


# ------------------------------------------------------------------ description


def test_validate_fmu_reports_no_problems(chassis_fmu):
    path, _, _ = chassis_fmu
    assert validate_fmu(str(path)) == []


def test_description_declares_a_cosimulation_and_model_exchange_chassis(chassis_fmu):
    path, md, _ = chassis_fmu
    assert md.modelName == "TDVASS chassis"
    assert md.coSimulation is not None and md.coSimulation.modelIdentifier == "tdvass"
    # Model Exchange over 19 states, no event indicators.
    assert md.modelExchange is not None and md.modelExchange.modelIdentifier == "tdvass"
    assert [d.variable.derivative.name for d in md.derivatives][:6] == POSITIONS + RATES
    assert len(md.derivatives) == 19
    assert not md.eventIndicators
    with zipfile.ZipFile(path) as z:
        xml = z.read("modelDescription.xml").decode()
    assert "<ModelExchange" in xml
    cs = md.coSimulation
    assert cs.maxOutputDerivativeOrder == 0
    assert cs.providesIntermediateUpdate is False
    assert cs.canHandleVariableCommunicationStepSize is True
    # Exact directional derivatives in Model Exchange, none in Co-Simulation.
    model_exchange = re.search(r"<ModelExchange [^>]*>", xml).group(0)
    co_simulation = re.search(r"<CoSimulation [^>]*>", xml).group(0)
    if md.fmiVersion == "2.0":
        assert cs.canInterpolateInputs is True
        assert 'providesDirectionalDerivative="false"' in co_simulation
        assert 'providesDirectionalDerivative="true"' in model_exchange
        assert 'canGetAndSetFMUstate="true"' in xml and 'canSerializeFMUstate="true"' in xml
    else:
        assert 'providesDirectionalDerivatives="false"' in co_simulation
        assert 'providesDirectionalDerivatives="true"' in model_exchange
        assert 'canGetAndSetFMUState="true"' in xml and 'canSerializeFMUState="true"' in xml
    variables = {v.name: v for v in md.modelVariables}
    for name in GEOMETRY:
        assert variables[name].causality == "parameter" and variables[name].variability == "fixed", name
    for name in FORCES:
        assert variables[name].causality == "input" and float(variables[name].start) == 0.0, name
    p = defaults(md)
    assert p["mass"] == 4 * 345.0
    assert p["pitch_inertia"] == pytest.approx(p["mass"] * p["a"] * p["b"], rel=1e-15)
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    assert outputs == ATTACHMENT + POSITIONS + RATES + ACCELERATIONS + [
        "seat_acceleration", "rms_heave_acceleration", "rms_pitch_acceleration", "rms_roll_acceleration",
        "weighted_seat_acceleration", "rms_weighted_seat_acceleration", "seat_vibration_dose_value"]
    for absent in ["variant", "m_s", "x_g", "body_force"]:
        assert absent not in variables, absent


def test_model_structure(chassis_fmu):
    """The attachment points and the motion depend on no input (a car of
    corners and chassis has no algebraic loop), only on the continuous
    states; the accelerations and the seat's depend directly on the four
    forces; the W_k-weighted one, an output of the filter's states, on
    those states."""
    _, md, _ = chassis_fmu
    outputs = {o.variable.name: o for o in md.outputs}
    assert set(outputs) == {v.name for v in md.modelVariables if v.causality == "output"}
    for name, output in outputs.items():
        if name in FEEDTHROUGH:
            assert [d.name for d in output.dependencies] == FORCES, name
            assert output.dependenciesKind == ["fixed"] * 4, name
        else:
            assert output.dependencies, name
            assert all(d.causality in ("output", "local") for d in output.dependencies), name
    initial = {u.variable.name: u for u in md.initialUnknowns}
    assert set(outputs) <= set(initial)
    assert all(md_v.causality == "local" for md_v in
               (u.variable for u in md.initialUnknowns) if md_v.name not in outputs)
    body = ["mass", "a", "b", "track_front", "track_rear", "pitch_inertia", "roll_inertia"]
    for name in ACCELERATIONS:
        assert [d.name for d in initial[name].dependencies] == body + FORCES, name
    assert [d.name for d in initial["seat_acceleration"].dependencies] == body + ["seat_x", "seat_y"] + FORCES
    for name in ATTACHMENT + POSITIONS + RATES + ["weighted_seat_acceleration"]:
        assert initial[name].dependencies == [], name


# ------------------------------------------------------------------ closed-form motion


@pytest.mark.parametrize("corner", CORNERS)
@pytest.mark.parametrize("params", ["default", "other"])
def test_a_held_force_moves_the_body_in_closed_form(make_chassis, chassis_fmu, corner, params):
    """A force held at one corner from t = 0: heave, pitch and roll are
    α t²/2, their rates α t; the attachment points move as z + x θ + y φ."""
    _, md, _ = chassis_fmu
    p = OTHER if params == "other" else defaults(md)
    force = 1234.5
    chassis = make_chassis().start(**(OTHER if params == "other" else {}), **{f"force_{corner}": force})
    alpha = accelerations(p, {corner: force})
    for got, expected in zip(chassis.get(*ACCELERATIONS), alpha):
        assert close(got, expected, 1e-13), (got, expected)
    assert chassis.get(*POSITIONS, *RATES) == [0.0] * 6
    h, n = 1e-3, 250
    for k in range(1, n + 1):
        chassis.step(h)
    t = n * h
    positions, rates = chassis.get(*POSITIONS), chassis.get(*RATES)
    for name, got, a in zip(POSITIONS, positions, alpha):
        assert close(got, a * t * t / 2, 1e-12), (name, got, a * t * t / 2)
    for name, got, a in zip(RATES, rates, alpha):
        assert close(got, a * t, 1e-12), (name, got, a * t)
    z, theta, phi = positions
    dz, dtheta, dphi = rates
    scale = abs(z) + abs(theta) + abs(phi)
    for c, (x, y) in corner_positions(p).items():
        displacement, velocity = chassis.get(f"displacement_{c}", f"velocity_{c}")
        assert displacement == pytest.approx(z + x * theta + y * phi, rel=1e-13, abs=1e-15 * scale), c
        assert velocity == pytest.approx(dz + x * dtheta + y * dphi, rel=1e-13, abs=1e-15 * scale), c
    # The accelerations are constant; their running RMS is their magnitude.
    for name, a in zip(["rms_heave_acceleration", "rms_pitch_acceleration", "rms_roll_acceleration"], alpha):
        assert close(chassis.get(name)[0], abs(a), 1e-12), name


def test_a_ramped_force_moves_the_body_as_a_cubic(make_chassis, chassis_fmu):
    """FMI 2.0 fmi2SetRealInputDerivatives (order 1): the force F0 + r t,
    so q = α(F0) t²/2 + α(r) t³/6 in one step and, the derivative kept,
    over several; setting the force again holds it. FMI 3.0 has no input
    derivatives (no fmi3SetInputDerivatives, and the chassis offers no
    intermediate update)."""
    _, md, _ = chassis_fmu
    if md.fmiVersion == "3.0":
        pytest.skip("FMI 3.0 has no input derivatives")
    p = defaults(md)
    f0, rate = 300.0, 4000.0
    # One step.
    chassis = make_chassis().start(force_fr=f0)
    chassis.ramp(force_fr=rate)
    t = 0.1
    chassis.step(t)
    held, ramp = accelerations(p, {"fr": f0}), accelerations(p, {"fr": rate})
    for name, got, a0, a1 in zip(POSITIONS, chassis.get(*POSITIONS), held, ramp):
        assert close(got, a0 * t * t / 2 + a1 * t ** 3 / 6, 1e-12), name
    for name, got, a0, a1 in zip(RATES, chassis.get(*RATES), held, ramp):
        assert close(got, a0 * t + a1 * t * t / 2, 1e-12), name
    # The force reached F0 + r t: the accelerations show it.
    for name, got, a0, a1 in zip(ACCELERATIONS, chassis.get(*ACCELERATIONS), held, ramp):
        assert close(got, a0 + a1 * t, 1e-13), name
    # From rest, a ramp alone over 100 steps of 1 ms: t³/6.
    chassis = make_chassis("steps").start()
    chassis.ramp(force_rl=rate)
    for _ in range(100):
        chassis.step(1e-3)
    t = chassis.time
    for name, got, a1 in zip(POSITIONS, chassis.get(*POSITIONS), accelerations(p, {"rl": rate})):
        assert close(got, a1 * t ** 3 / 6, 1e-12), name
    # Set again, the force holds from there on.
    z, dz = chassis.get("heave", "heave_velocity")
    chassis.set(force_rl=rate * t)
    chassis.step(0.05)
    a = rate * t / p["mass"]
    assert close(chassis.get("heave")[0], z + dz * 0.05 + a * 0.05 ** 2 / 2, 1e-12)
    assert close(chassis.get("heave_acceleration")[0], a, 1e-13)
    # An order above 1 is ignored with a warning naming the input.
    chassis.fmu.setRealInputDerivatives([chassis.vr["force_fl"]], [2], [1.0])
    status, category, message = chassis.last()
    assert status == FMI2_WARNING and "force_fl" in message and "ignored" in message, chassis.last()


def test_a_force_set_at_a_communication_point_reaches_the_accelerations_at_once(make_chassis, chassis_fmu):
    """The accelerations and the seat's show a force set after
    initialization (at t = 0 and at later communication points) before
    any step."""
    _, md, _ = chassis_fmu
    p = defaults(md)
    chassis = make_chassis().start()
    assert chassis.get(*FEEDTHROUGH) == [0.0] * 4
    for k, forces in enumerate([{"fl": 800.0}, {"fl": 800.0, "rr": -350.0}, {"fr": 120.0, "rl": 2000.0}]):
        if k:
            chassis.step(1e-2)
        weighted = chassis.get("weighted_seat_acceleration")
        chassis.set(**{f"force_{c}": forces.get(c, 0.0) for c in CORNERS})
        alpha = accelerations(p, forces)
        got = chassis.get(*ACCELERATIONS, "seat_acceleration")
        for name, g, a in zip(ACCELERATIONS, got, alpha):
            assert close(g, a, 1e-13), (k, name, g, a)
        seat = alpha[0] + p["seat_x"] * alpha[1] + p["seat_y"] * alpha[2]
        assert close(got[3], seat, 1e-13), (k, got[3], seat)
        # W_k is strictly proper (its 100 Hz low-pass): a_w is an output
        # of the filter's states and does not jump with the force, as its
        # declaration (no dependencies) says; it follows over the step.
        assert chassis.get("weighted_seat_acceleration") == weighted, k
    chassis.step(1e-2)
    assert chassis.get("weighted_seat_acceleration") != weighted


def test_with_the_default_pitch_inertia_a_front_force_leaves_the_rear_axle_at_rest(make_chassis):
    """I_θ = m a b: a front force moves the rear axle's middle not at all
    (the roll tilts it)."""
    chassis = make_chassis().start(force_fl=2500.0)
    for _ in range(300):
        chassis.step(1e-3)
    rl, rr, fl = chassis.get("displacement_rl", "displacement_rr", "displacement_fl")
    assert abs((rl + rr) / 2) <= 1e-14 * fl, (rl, rr, fl)
    assert rl > 0.0 > rr
    vrl, vrr, vfl = chassis.get("velocity_rl", "velocity_rr", "velocity_fl")
    assert abs((vrl + vrr) / 2) <= 1e-14 * vfl, (vrl, vrr, vfl)
    # Another pitch inertia couples them: the rear axle's middle moves.
    other = make_chassis("coupled").start(force_fl=2500.0, pitch_inertia=2 * 4 * 345.0 * 1.3 * 1.3)
    for _ in range(300):
        other.step(1e-3)
    rl, rr = other.get("displacement_rl", "displacement_rr")
    assert (rl + rr) / 2 > 0.1 * fl


# ------------------------------------------------------------------ the communication grid

GRIDS = {
    "1 ms": [1e-3] * 300,
    "0.7 ms": [0.7e-3] * 428 + [0.3 - 428 * 0.7e-3],
    "varying": [(0.2e-3, 1.3e-3, 0.5e-3, 2.0e-3)[k % 4] for k in range(300)],
}
# The comfort measures too: a_w is integrated exactly, its RMS and VDV by
# Gauss-Legendre inside each step (about 5e-14 apart between these grids).
GRID_OUTPUTS = POSITIONS + RATES + ATTACHMENT + [
    "rms_heave_acceleration", "rms_pitch_acceleration", "rms_roll_acceleration", "weighted_seat_acceleration",
    "rms_weighted_seat_acceleration", "seat_vibration_dose_value"]


def run_on(chassis, steps, fmi2_ramp):
    chassis.start(force_fl=900.0, force_rr=-400.0, force_rl=150.0)
    if fmi2_ramp:
        chassis.ramp(force_fr=3000.0)
    for h in steps:
        chassis.step(h)
    return chassis.time, chassis.get(*GRID_OUTPUTS)


def test_the_result_does_not_depend_on_the_communication_grid(make_chassis, chassis_fmu):
    """Held forces (FMI 2.0: one ramped too) over 0.3 s on three grids (1 ms,
    0.7 ms and a short last step, and steps cycling through 0.2, 1.3, 0.5
    and 2 ms): the same final motion and comfort measures to 1e-12, and the
    motion on the closed form."""
    _, md, _ = chassis_fmu
    ramp = md.fmiVersion == "2.0"
    p = defaults(md)
    results = {name: run_on(make_chassis(name), steps, ramp) for name, steps in GRIDS.items()}
    t_ref, ref = results["1 ms"]
    for grid in ["0.7 ms", "varying"]:
        t, other = results[grid]
        assert t == pytest.approx(t_ref, abs=1e-15), grid
        for name, a, b in zip(GRID_OUTPUTS, ref, other):
            assert close(b, a, 1e-12), (grid, name, a, b)
    held = accelerations(p, {"fl": 900.0, "rr": -400.0, "rl": 150.0})
    ramped = accelerations(p, {"fr": 3000.0 if ramp else 0.0})
    for (t, values) in results.values():
        for name, got, a0, a1 in zip(POSITIONS, values, held, ramped):
            assert close(got, a0 * t * t / 2 + a1 * t ** 3 / 6, 1e-12), (t, name)


# ------------------------------------------------------------------ FMU states

STATE_OUTPUTS = POSITIONS + RATES + ATTACHMENT + ["rms_heave_acceleration", "rms_roll_acceleration",
                                                  "weighted_seat_acceleration", "rms_weighted_seat_acceleration",
                                                  "seat_vibration_dose_value"]


def continue_run(chassis):
    rows = []
    for k in range(20):
        chassis.set(force_rl=80.0 + 5.0 * k, force_fl=300.0 - 7.0 * k)
        chassis.step(2.5e-3)
        rows.append(chassis.get(*STATE_OUTPUTS))
    return rows


def test_a_state_set_or_deserialized_continues_bit_identically(make_chassis):
    chassis = make_chassis().start(force_fl=300.0, force_rr=-120.0)
    if not chassis.fmi3:
        chassis.ramp(force_fr=50.0)
    for k in range(70):
        chassis.set(force_fr=40.0 * (k % 5))
        chassis.step(1e-3)
    t0 = chassis.time
    state = chassis.get_state()
    data = chassis.serialize(state)
    first = continue_run(chassis)
    assert first[-1][0] != 0.0 and first[-1][-1] > 0.0
    chassis.set_state(state)
    chassis.time = t0
    assert continue_run(chassis) == first
    chassis.free_state(state)
    fresh = make_chassis("fresh")
    restored = fresh.deserialize(data)
    fresh.set_state(restored)
    fresh.free_state(restored)
    fresh.time = t0
    assert continue_run(fresh) == first


# ------------------------------------------------------------------ refused values


def refused(chassis, **values):
    error = FMI3_ERROR if chassis.fmi3 else FMI2_ERROR
    with pytest.raises(FMICallException) as caught:
        chassis.set(**values)
    assert caught.value.status == error
    status, category, message = chassis.last()
    assert status == error and category == "logStatusError", chassis.last()
    return message


@pytest.mark.parametrize("name, value, reason", [
    ("mass", 0.0, "must be > 0"),
    ("mass", -1380.0, "must be > 0"),
    ("pitch_inertia", -1.0, "must be > 0"),
    ("roll_inertia", -400.0, "must be > 0"),
    ("roll_inertia", NAN, "must be finite"),
    ("a", -0.1, "must be >= 0"),
    ("seat_y", INF, "must be finite"),
    ("force_fl", NAN, "must be finite"),
    ("force_rr", -INF, "must be finite"),
], ids=["mass=0", "mass<0", "pitch_inertia<0", "roll_inertia<0", "roll_inertia=nan", "a<0", "seat_y=inf",
        "force_fl=nan", "force_rr=-inf"])
def test_a_bad_value_is_refused_naming_the_variable(make_chassis, chassis_fmu, name, value, reason):
    _, md, _ = chassis_fmu
    chassis = make_chassis()
    chassis.enter()
    message = refused(chassis, **{name: value})
    assert f"`{name}`" in message and reason in message, message
    chassis.exit()  # nothing was applied
    start = {v.name: float(v.start) for v in md.modelVariables if v.name in GEOMETRY + FORCES}
    assert chassis.get(name) == [start[name]]


@pytest.mark.parametrize("name, value", [("force_fr", NAN), ("force_rl", INF)])
def test_a_non_finite_force_while_stepping_is_refused_and_the_run_goes_on(make_chassis, name, value):
    chassis = make_chassis().start(force_fl=500.0)
    chassis.step(1e-2)
    before = chassis.get(*STATE_OUTPUTS, *FORCES)
    message = refused(chassis, **{name: value})
    assert f"`{name}`" in message and "must be finite" in message, message
    assert chassis.get(*STATE_OUTPUTS, *FORCES) == before
    chassis.step(1e-2)
    assert chassis.get("heave")[0] > before[0] > 0.0


def test_a_zero_wheelbase_is_refused_at_the_end_of_initialization_naming_b(make_chassis):
    chassis = make_chassis()
    chassis.enter()
    chassis.set(a=0.0, b=0.0)
    error = FMI3_ERROR if chassis.fmi3 else FMI2_ERROR
    with pytest.raises(FMICallException) as caught:
        chassis.exit()
    assert caught.value.status == error
    status, category, message = chassis.last()
    assert status == error and category == "logStatusError", chassis.last()
    assert "`b`" in message and "wheelbase" in message, message
    chassis.set(b=1.3)  # still in initialization mode: corrected, it initializes
    chassis.exit()
    chassis.set(force_rl=100.0)
    chassis.step(1e-2)
    assert chassis.get("pitch")[0] < 0.0
