"""The corner FMUs (target/fmu/tdvass-corner.fmu, FMI 2.0, and
tdvass-corner-fmi3.fmu, FMI 3.0; both Co-Simulation and Model Exchange; here in Co-Simulation) driven from fmpy:
their descriptions, the body attachment (inputs body_displacement and
body_velocity, output body_force), the delayed and phase-shifted road, the
static load under the unilateral tire, refused values, and the quarter car
rebuilt as a corner under a point mass in a master's Jacobi loop."""

import math
import re
import zipfile

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from fmu_helpers import Slave

FMI2_ERROR = FMI3_ERROR = 3
G0 = 9.80665
NAN, INF = float("nan"), float("inf")

CORNER_STATES = ["x_h", "v_h", "x_t", "v_t"]


class Corner:
    """One Co-Simulation instance of a corner FMU, FMI 2.0 or 3.0, with
    name-based access and its log, (status, category, message)."""

    def __init__(self, unzipdir, md, name="corner"):
        self.md = md
        self.fmi3 = md.fmiVersion == "3.0"
        self.types = {v.name: v.type for v in md.modelVariables}
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.time = 0.0
        if self.fmi3:
            self._messages = []
            self.fmu = FMU3Slave(
                guid=md.guid,
                unzipDirectory=unzipdir,
                modelIdentifier=md.coSimulation.modelIdentifier,
                instanceName=name,
            )
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

    def setup(self, stop_time=None):
        """FMI 2.0: fmi2SetupExperiment (FMI 3.0 takes the times on entering
        initialization)."""
        self.stop_time = stop_time
        if not self.fmi3:
            self.fmu.setupExperiment(startTime=0.0, stopTime=stop_time)

    def enter(self):
        if self.fmi3:
            self.fmu.enterInitializationMode(startTime=0.0, stopTime=self.stop_time)
        else:
            self.fmu.enterInitializationMode()

    def exit(self):
        self.fmu.exitInitializationMode()

    def start(self, stop_time=None, **values):
        self.setup(stop_time)
        self.set(**values)
        self.enter()
        self.exit()
        self.time = 0.0
        return self

    def set(self, **values):
        """Ints for the Integer (FMI 3.0: Enumeration, Int32) variables."""
        for name, value in values.items():
            vr, kind = [self.vr[name]], self.types[name]
            if kind in ("Real", "Float64"):
                (self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal)(vr, [float(value)])
            elif kind == "Enumeration":
                self.fmu.setInt64(vr, [value])
            elif kind == "Int32":
                self.fmu.setInt32(vr, [value])
            else:
                self.fmu.setInteger(vr, [value])

    def get(self, *names) -> list[float]:
        vrs = [self.vr[n] for n in names]
        return list(self.fmu.getFloat64(vrs) if self.fmi3 else self.fmu.getReal(vrs))

    def get_int(self, name) -> int:
        vrs = [self.vr[name]]
        return (self.fmu.getInt32(vrs) if self.fmi3 else self.fmu.getInteger(vrs))[0]

    def step_to(self, t):
        self.fmu.doStep(self.time, t - self.time)
        self.time = t

    def free(self):
        if self.fmu is not None:
            self.fmu.freeInstance()
            self.fmu = None


@pytest.fixture(scope="module", params=["2.0", "3.0"], ids=["fmi2", "fmi3"])
def corner_fmu(request, corner_file, corner_fmi3_file, tmp_path_factory):
    """(path, model description, unzip directory) of one corner FMU."""
    path = corner_file if request.param == "2.0" else corner_fmi3_file
    md = read_model_description(str(path))
    assert md.fmiVersion == request.param
    return path, md, extract(str(path), unzipdir=str(tmp_path_factory.mktemp("corner")))


@pytest.fixture
def make_corner(corner_fmu):
    """Factory of corner instances, all freed at the end of the test."""
    _, md, unzipdir = corner_fmu
    made = []

    def make(name="corner"):
        corner = Corner(unzipdir, md, name=name)
        made.append(corner)
        return corner

    yield make
    for corner in made:
        corner.free()


def start_of(md, name) -> float:
    return float(next(v for v in md.modelVariables if v.name == name).start)


def attachment_force(k_s, c_s, displacement, velocity, x_h, v_h):
    """The suspension's force on the body, positive up, zero at the static
    equilibrium: the spring and the damper between the body's attachment
    point and the mass the suspension joins (the absorber x_h; CS: the
    wheel, which x_h mirrors)."""
    return -k_s * (displacement - x_h) - c_s * (velocity - v_h)


# ------------------------------------------------------------------ description


def test_validate_fmu_reports_no_problems(corner_fmu):
    path, _, _ = corner_fmu
    assert validate_fmu(str(path)) == []


def test_description_declares_a_cosimulation_and_model_exchange_corner(corner_fmu):
    path, md, _ = corner_fmu
    assert md.modelName == "TDVASS corner"
    assert md.coSimulation is not None and md.coSimulation.modelIdentifier == "tdvass"
    # Model Exchange over its own 7 states (the body's coordinates are
    # inputs), with exact directional derivatives
    # (test_model_exchange_masters.py).
    assert md.modelExchange is not None and md.modelExchange.modelIdentifier == "tdvass"
    assert [d.variable.derivative.name for d in md.derivatives] == CORNER_STATES + [
        "integral_suspension_deflection_squared", "integral_tire_deflection_squared", "contact_loss_time"]
    with zipfile.ZipFile(path) as z:
        xml = z.read("modelDescription.xml").decode()
    # (fmpy reads FMI 3.0's plural attribute as FMI 2.0's singular one.)
    model_exchange = re.search(r"<ModelExchange [^>]*>", xml).group(0)
    assert re.search(r'providesDirectionalDerivatives?="true"', model_exchange), model_exchange
    variables = {v.name: v for v in md.modelVariables}
    assert "m_s" not in variables and "x_s" not in variables and "body_acceleration" not in variables
    for name in ["static_load", "road_delay", "road_phase"]:
        assert variables[name].causality == "parameter", name
    assert float(variables["static_load"].start) == pytest.approx(345 * G0, rel=1e-15)
    assert float(variables["road_delay"].start) == float(variables["road_phase"].start) == 0.0
    for name in ["body_displacement", "body_velocity", "x_g"]:
        assert variables[name].causality == "input", name
    assert variables["body_force"].causality == "output"
    outputs = {o.variable.name: o for o in md.outputs}
    force = outputs["body_force"]
    assert [d.name for d in force.dependencies] == [*CORNER_STATES, "body_displacement", "body_velocity"]
    assert force.dependenciesKind == ["dependent"] * 4 + ["fixed", "fixed"]
    assert [d.name for d in outputs["suspension_deflection"].dependencies] == [*CORNER_STATES, "body_displacement"]
    # The states depend on no input directly, only on themselves.
    for name in CORNER_STATES:
        assert [d.name for d in outputs[name].dependencies] == [name], name


def test_the_quarter_cars_body_is_the_default_static_load(corner_fmu, model_description):
    _, md, _ = corner_fmu
    m_s = float(next(v for v in model_description.modelVariables if v.name == "m_s").start)
    assert start_of(md, "static_load") / G0 == pytest.approx(m_s, rel=1e-15)


# ------------------------------------------------------------------ at rest


@pytest.mark.parametrize("road", [{"road_amplitude": 0.0}, {"road": 0}], ids=["harmonic amplitude 0", "input x_g 0"])
def test_at_rest_the_force_and_the_states_stay_zero(make_corner, road):
    corner = make_corner().start(stop_time=1.0, **road)
    names = ["body_force", "suspension_deflection", "tire_deflection", "road_displacement", *CORNER_STATES]
    assert corner.get(*names) == [0.0] * len(names)
    for k in range(1, 201):
        corner.step_to(k * 2.5e-3)
        assert corner.get(*names) == [0.0] * len(names), corner.time
    assert corner.get("rms_suspension_deflection", "rms_tire_deflection") == [0.0, 0.0]
    assert corner.get_int("lift_off_count") == 0


# ------------------------------------------------------------------ body attachment

STARTS = {"x_h_start": 0.003, "v_h_start": -0.04, "x_t_start": -0.002, "v_t_start": 0.05}


@pytest.mark.parametrize("variant", [1, 2, 3], ids=["CS", "PVASS", "TDVASS"])
def test_body_force_follows_the_body_inputs_in_initialization_mode(make_corner, corner_fmu, variant):
    """In initialization mode the body inputs reach body_force and
    suspension_deflection without a step: the spring and the damper between
    the attachment point and the absorber (CS: the wheel)."""
    _, md, _ = corner_fmu
    k_s, c_s = start_of(md, "k_s"), start_of(md, "c_s")
    corner = make_corner()
    corner.setup(stop_time=1.0)
    corner.set(variant=variant, road=0, **STARTS)
    corner.enter()
    joined = ("x_t_start", "v_t_start") if variant == 1 else ("x_h_start", "v_h_start")
    for displacement, velocity in [(0.0, 0.0), (0.01, 0.0), (0.0, 0.2), (-0.015, 0.3)]:
        corner.set(body_displacement=displacement, body_velocity=velocity)
        expected = attachment_force(k_s, c_s, displacement, velocity, *(STARTS[n] for n in joined))
        force, deflection = corner.get("body_force", "suspension_deflection")
        assert force == pytest.approx(expected, rel=1e-14, abs=1e-12), (displacement, velocity)
        assert deflection == pytest.approx(displacement - STARTS["x_t_start"], rel=1e-14, abs=1e-16)
    corner.exit()
    force, x_h, v_h = corner.get("body_force", "x_h", "v_h")
    assert force == pytest.approx(attachment_force(k_s, c_s, -0.015, 0.3, x_h, v_h), rel=1e-14)


@pytest.mark.parametrize("variant", [1, 3], ids=["CS", "TDVASS"])
def test_body_force_follows_the_body_inputs_at_a_communication_point(make_corner, corner_fmu, variant):
    _, md, _ = corner_fmu
    k_s, c_s = start_of(md, "k_s"), start_of(md, "c_s")
    corner = make_corner().start(stop_time=1.0, variant=variant)
    for t in [0.0, 0.01]:
        if t > 0.0:
            corner.step_to(t)
        x_h, v_h, x_t = corner.get("x_h", "v_h", "x_t")
        for displacement, velocity in [(0.01, 0.0), (0.0, 0.2), (-0.015, 0.3)]:
            corner.set(body_displacement=displacement, body_velocity=velocity)
            force, deflection = corner.get("body_force", "suspension_deflection")
            assert deflection == pytest.approx(displacement - x_t, rel=1e-14, abs=1e-16), (t, displacement)
            assert force == pytest.approx(attachment_force(k_s, c_s, displacement, velocity, x_h, v_h),
                                          rel=1e-14), (t, displacement, velocity)


def test_the_attachment_point_moves_at_body_velocity_over_a_step(make_corner, corner_fmu):
    _, md, _ = corner_fmu
    k_s, c_s = start_of(md, "k_s"), start_of(md, "c_s")
    corner = make_corner().start(stop_time=1.0)
    h = 1e-3
    for k, (displacement, velocity) in enumerate([(0.01, 0.2), (0.02, -0.1), (-0.005, 0.0)]):
        corner.set(body_displacement=displacement, body_velocity=velocity)
        corner.step_to((k + 1) * h)
        force, deflection, x_t, x_h, v_h = corner.get("body_force", "suspension_deflection", "x_t", "x_h", "v_h")
        moved = displacement + velocity * h
        assert deflection + x_t == pytest.approx(moved, rel=1e-13, abs=1e-17), k
        assert force == pytest.approx(attachment_force(k_s, c_s, moved, velocity, x_h, v_h), rel=1e-12), k


# ------------------------------------------------------------------ corner + point mass = quarter car

QUARTER_CAR_OUTPUTS = ["x_t", "rms_suspension_deflection"]
JACOBI_DURATION = 1.0
SAMPLE = 1e-3


@pytest.fixture(scope="module")
def quarter_car(unzipdir, model_description):
    """The quarter car's x_t every 1 ms over 1 s and its final RMS SDD."""
    slave = Slave(unzipdir, model_description, name="quarter")
    slave.start(stop_time=JACOBI_DURATION)
    n = round(JACOBI_DURATION / SAMPLE)
    x_t = []
    for k in range(1, n + 1):
        slave.step_to(k * SAMPLE)
        x_t += slave.get(["x_t"])
    rms = slave.get(["rms_suspension_deflection"])[0]
    slave.free()
    return np.array(x_t), rms


def corner_under_a_point_mass(corner, mass, h):
    """A master's Jacobi loop: at each communication point the body inputs
    from the body's state there, the corner's body_force read, both stepped
    (the point mass exactly under that force held). x_t every 1 ms and the
    final RMS SDD."""
    corner.start(stop_time=JACOBI_DURATION)
    n, every = round(JACOBI_DURATION / h), round(SAMPLE / h)
    x, v, x_t = 0.0, 0.0, []
    for k in range(1, n + 1):
        corner.set(body_displacement=x, body_velocity=v)
        (force,) = corner.get("body_force")
        corner.step_to(k * h)
        a = force / mass
        x, v = x + v * h + 0.5 * a * h * h, v + a * h
        if k % every == 0:
            x_t.append(corner.get("x_t")[0])
    return np.array(x_t), corner.get("rms_suspension_deflection")[0]


def point_mass_errors(make_corner, corner_fmu, quarter_car, h):
    """Relative errors of the corner under the point mass against the quarter
    car: max |x_t| difference over max |x_t|, and the final RMS SDD's."""
    _, md, _ = corner_fmu
    x_ref, rms_ref = quarter_car
    x_t, rms = corner_under_a_point_mass(make_corner(), start_of(md, "static_load") / G0, h)
    assert len(x_t) == len(x_ref)
    return float(np.abs(x_t - x_ref).max() / np.abs(x_ref).max()), abs(rms - rms_ref) / rms_ref


def test_corner_under_a_point_mass_converges_to_the_quarter_car(make_corner, corner_fmu, quarter_car):
    """First order in the communication step: halving it roughly halves the
    errors (the Jacobi master holds the force over each step)."""
    coarse = point_mass_errors(make_corner, corner_fmu, quarter_car, 1e-3)
    fine = point_mass_errors(make_corner, corner_fmu, quarter_car, 5e-4)
    print(f"\nFMI {corner_fmu[1].fmiVersion} corner + point mass, relative errors (x_t, RMS SDD): "
          f"h = 1 ms {coarse[0]:.3g}, {coarse[1]:.3g}; h = 0.5 ms {fine[0]:.3g}, {fine[1]:.3g}")
    for name, c, f in zip(QUARTER_CAR_OUTPUTS, coarse, fine):
        assert 0.0 < c < 1e-2, (name, c)
        assert f < 0.7 * c, (name, c, f)
        assert f > 0.3 * c, (name, c, f)  # first order, not an accident


# ------------------------------------------------------------------ the road as this wheel sees it

DELAY = 0.05  # 50 steps of 1 ms
PHASE = 0.7


def road_displacements(corner, n, h=1e-3):
    """road_displacement at t = 0 and the n following communication points."""
    out = corner.get("road_displacement")
    for k in range(1, n + 1):
        corner.step_to(k * h)
        out += corner.get("road_displacement")
    return np.array(out)


def test_road_delay_delays_the_harmonic_road(make_corner):
    n, lag = 200, round(DELAY / 1e-3)
    undelayed = road_displacements(make_corner("front").start(stop_time=1.0), n)
    delayed = road_displacements(make_corner("rear").start(stop_time=1.0, road_delay=DELAY), n)
    assert np.abs(delayed[lag:] - undelayed[: n + 1 - lag]).max() <= 1e-12
    assert np.abs(undelayed).max() > 0.01  # the road moves


def test_road_phase_shifts_the_delayed_harmonic_road(make_corner, corner_fmu):
    _, md, _ = corner_fmu
    amplitude, omega = start_of(md, "road_amplitude"), start_of(md, "road_angular_frequency")
    n = 200
    t = np.arange(n + 1) * 1e-3
    shifted = road_displacements(make_corner().start(stop_time=1.0, road_delay=DELAY, road_phase=PHASE), n)
    assert np.abs(shifted - amplitude * np.sin(omega * (t - DELAY) + PHASE)).max() <= 1e-12
    plain = road_displacements(make_corner().start(stop_time=1.0), n)
    assert np.abs(plain - amplitude * np.sin(omega * t)).max() <= 1e-12


# ------------------------------------------------------------------ static load, unilateral tire


@pytest.mark.parametrize("static_load, lifts_off", [(200.0, True), (1e5, False)])
def test_static_load_decides_the_lift_off(make_corner, static_load, lifts_off):
    """The body held at its equilibrium, a 2 cm road at 60 rad/s (near the
    wheel hop): a light corner's wheel leaves the road, a heavy one's does
    not."""
    corner = make_corner().start(stop_time=1.0, tire_contact=1, static_load=static_load,
                                 road_amplitude=0.02, road_angular_frequency=60.0)
    for k in range(1, 1001):
        corner.step_to(k * 1e-3)
    count, flight = corner.get_int("lift_off_count"), corner.get("contact_loss_time")[0]
    if lifts_off:
        assert count > 0 and flight > 0.0, (count, flight)
    else:
        assert count == 0 and flight == 0.0, (count, flight)


# ------------------------------------------------------------------ refused values


def refused(corner, error, **values):
    with pytest.raises(FMICallException) as caught:
        corner.set(**values)
    assert caught.value.status == error
    status, category, message = corner.last()
    assert status == error and category == "logStatusError", corner.last()
    return message


@pytest.mark.parametrize("name", ["body_displacement", "body_velocity"])
@pytest.mark.parametrize("value", [NAN, INF, -INF], ids=["nan", "inf", "-inf"])
def test_a_non_finite_body_input_is_refused(make_corner, name, value):
    corner = make_corner().start(stop_time=1.0)
    corner.set(body_displacement=0.01, body_velocity=0.1)
    corner.step_to(1e-3)
    before = corner.get("body_displacement", "body_velocity", "body_force", "x_t")
    message = refused(corner, FMI3_ERROR if corner.fmi3 else FMI2_ERROR, **{name: value})
    assert f"`{name}`" in message and "must be finite" in message, message
    assert corner.get("body_displacement", "body_velocity", "body_force", "x_t") == before
    corner.step_to(2e-3)  # the instance steps on with the values it had
    assert all(math.isfinite(v) for v in corner.get("body_force", "x_t", "suspension_deflection"))


@pytest.mark.parametrize("value, reason", [(0.0, "must be > 0"), (-345 * G0, "must be > 0"),
                                           (NAN, "must be finite")], ids=["0", "negative", "nan"])
@pytest.mark.parametrize("mode", ["instantiated", "initialization"])
def test_a_static_load_that_is_not_positive_is_refused(make_corner, value, reason, mode):
    corner = make_corner()
    corner.setup(stop_time=1.0)
    if mode == "initialization":
        corner.enter()
    message = refused(corner, FMI3_ERROR if corner.fmi3 else FMI2_ERROR, static_load=value)
    assert "`static_load`" in message and reason in message, message
    if mode == "instantiated":
        corner.enter()
    corner.exit()  # nothing was applied
    assert corner.get("static_load") == [345 * G0]


def test_a_negative_road_delay_is_refused(make_corner):
    corner = make_corner()
    corner.setup(stop_time=1.0)
    message = refused(corner, FMI3_ERROR if corner.fmi3 else FMI2_ERROR, road_delay=-1e-3)
    assert "`road_delay`" in message and "must be >= 0" in message, message


def test_a_tiny_static_load_is_named_if_refused(make_corner):
    corner = make_corner()
    corner.setup(stop_time=1.0)
    corner.set(static_load=1e-7)
    corner.enter()
    try:
        corner.exit()
    except FMICallException:
        message = corner.last()[2]
        assert "`static_load`" in message and "m_s" not in message, message
