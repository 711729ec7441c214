"""Model Exchange of the corner and the chassis: each FMU validated, each
integrated by fmpy's own solver against its Co-Simulation, and the full car
(one chassis, four corners, the parameters and connections of
full-car.ssp) integrated as one system of 47 states by one scipy solver
against the Co-Simulation car of examples/full_car.py; its Jacobian
assembled from the five FMUs' directional derivatives against central
differences."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, simulate_fmu
from fmpy.validation import validate_fmu

from fmu_helpers import REPO_ROOT
from me_master import ModelExchangeMaster

sys.path.insert(0, str(REPO_ROOT / "examples"))
import full_car  # noqa: E402

CORNERS = full_car.CORNERS


def test_the_component_fmus_validate_with_model_exchange(
    corner_file, corner_fmi3_file, chassis_file, chassis_fmi3_file
):
    from fmpy import read_model_description

    for fmu, states in [
        (corner_file, 7),
        (corner_fmi3_file, 7),
        (chassis_file, 19),
        (chassis_fmi3_file, 19),
    ]:
        assert validate_fmu(str(fmu)) == [], fmu.name
        md = read_model_description(str(fmu))
        assert md.modelExchange is not None and md.coSimulation is not None
        assert len(md.derivatives) == states, fmu.name
        # Both give exact partials in Model Exchange
        # (test_model_exchange_masters.py, and the assembled car's
        # Jacobian below). (fmpy reads FMI 3.0's plural attribute as FMI
        # 2.0's singular one: the XML is read here.)
        with zipfile.ZipFile(fmu) as z:
            xml = z.read("modelDescription.xml").decode()
        model_exchange = re.search(r"<ModelExchange [^>]*>", xml).group(0)
        assert re.search(r'providesDirectionalDerivatives?="true"', model_exchange), fmu.name


CORNER_OUTPUTS = ["x_t", "v_t", "body_force", "rms_suspension_deflection", "rms_tire_deflection"]


@pytest.mark.parametrize("which", ["fmi2", "fmi3"])
def test_the_corner_s_model_exchange_agrees_with_its_co_simulation(which, corner_file, corner_fmi3_file):
    """The harmonic road under a body moving on its own line: fmpy's CVode
    at rtol 1e-9 against the Co-Simulation at the FMU's default tolerance
    (both within 1e-6 of each value's scale)."""
    fmu = str(corner_file if which == "fmi2" else corner_fmi3_file)
    start = {"body_displacement": 0.002, "body_velocity": 0.0}
    runs = {
        kind: simulate_fmu(fmu, fmi_type=kind, stop_time=1.0, output_interval=1e-3, start_values=start,
                           relative_tolerance=1e-9, output=CORNER_OUTPUTS)
        for kind in ("ModelExchange", "CoSimulation")
    }
    me, cs = runs["ModelExchange"], runs["CoSimulation"]
    for name in CORNER_OUTPUTS:
        scale = np.max(np.abs(cs[name]))
        error = np.max(np.abs(me[name] - cs[name]))
        assert error <= 1e-6 * scale, (name, error, scale)


def test_the_chassis_s_model_exchange_agrees_with_its_co_simulation(chassis_file):
    """Constant forces: the Co-Simulation step is exact, so Model Exchange
    at rtol 1e-10 agrees to 1e-7 of each value's scale; the outputs of the
    W_k filter, which starts with a step of the seat acceleration at t = 0
    that fmpy's CVode resolves at its own step control, to 2e-5 (measured
    1.2e-5 for the RMS of a_w)."""
    start = {"force_fl": 400.0, "force_rr": -150.0, "force_fr": 80.0}
    outputs = ["heave", "pitch", "roll", "displacement_fl", "velocity_rr", "rms_heave_acceleration",
               "rms_roll_acceleration", "weighted_seat_acceleration", "rms_weighted_seat_acceleration",
               "seat_vibration_dose_value"]
    runs = {
        kind: simulate_fmu(str(chassis_file), fmi_type=kind, stop_time=1.0, output_interval=1e-2,
                           start_values=start, relative_tolerance=1e-10, output=outputs)
        for kind in ("ModelExchange", "CoSimulation")
    }
    me, cs = runs["ModelExchange"], runs["CoSimulation"]
    for name in outputs:
        scale = np.max(np.abs(cs[name]))
        assert scale > 0, name
        error = np.max(np.abs(me[name] - cs[name]))
        bound = 2e-5 if "weighted" in name or "dose" in name else 1e-7
        assert error <= bound * scale, (name, error, scale)


class Car:
    """The five Model Exchange instances of full-car.ssp with its
    parameters, and the connections between them."""

    def __init__(self, ssp: Path, work: Path, overrides: dict | None = None):
        components, connections = full_car.read_ssd(ssp)
        with zipfile.ZipFile(ssp) as archive:
            archive.extractall(work)
        self.parts = {}
        for instance, (source, parameters) in components.items():
            unzipdir = extract(str(work / source), unzipdir=str(work / instance))
            values = {**parameters, **(overrides or {}).get(instance, {})}
            self.parts[instance] = ModelExchangeMaster(work / source, values, unzipdir=unzipdir, name=instance)
        self.names = list(self.parts)
        self.slices, at = {}, 0
        for name in self.names:
            self.slices[name] = slice(at, at + self.parts[name].n)
            at += self.parts[name].n
        self.n = at
        # The chassis's outputs depend on its states alone, the corners'
        # body_force on their states and the body inputs: chassis first.
        vr = {name: {v.name: v.valueReference for v in part.md.modelVariables} for name, part in self.parts.items()}
        from_chassis = [(out, b, inp) for a, out, b, inp in connections if a == "chassis"]
        self.chassis_outputs = [vr["chassis"][out] for out, _, _ in from_chassis]
        self.corner_inputs = {
            c: ([vr[c][inp] for _, b, inp in from_chassis if b == c],
                [i for i, (_, b, _) in enumerate(from_chassis) if b == c])
            for c in CORNERS
        }
        to_chassis = [(a, out, inp) for a, out, b, inp in connections if b == "chassis"]
        self.force_order = [a for a, _, _ in to_chassis]
        self.force_vr = {a: [vr[a][out]] for a, out, _ in to_chassis}
        self.chassis_inputs = [vr["chassis"][inp] for _, _, inp in to_chassis]

    def state(self):
        return np.concatenate([self.parts[name].x for name in self.names])

    def set_point(self, t, y):
        """Time and states of every part, then the connections: the
        chassis's attachment points (its states alone) to the corners, the
        corners' forces (their states and those inputs) to the chassis."""
        for name in self.names:
            self.parts[name].set_point(t, y[self.slices[name]])
        chassis = self.parts["chassis"]
        motion = chassis.fmu.getReal(self.chassis_outputs)
        for corner, (vrs, at) in self.corner_inputs.items():
            self.parts[corner].fmu.setReal(vrs, [motion[i] for i in at])
        forces = [self.parts[c].fmu.getReal(self.force_vr[c])[0] for c in self.force_order]
        chassis.fmu.setReal(self.chassis_inputs, forces)

    def derivatives(self, t, y):
        self.set_point(t, y)
        dy = np.empty(self.n)
        for name in self.names:
            part = self.parts[name]
            part.fmu.getDerivatives(part.buffer, part.n)
            dy[self.slices[name]] = part.buffer[:]
        return dy

    def complete(self, t, y):
        self.set_point(t, y)
        for part in self.parts.values():
            part.complete()

    def jacobian(self, t, y):
        """∂(dy/dt)/∂y of the assembled car, from the parts' directional
        derivatives by the chain rule through the connections: each
        corner's derivatives and force depend on its states and its body
        inputs, which are the chassis's outputs of its states alone; the
        chassis's derivatives depend on its states and the forces."""
        self.set_point(t, y)
        chassis = self.parts["chassis"]
        ch = self.slices["chassis"]
        jac = np.zeros((self.n, self.n))
        jac[ch, ch] = chassis.partials(chassis.derivative_vrs, chassis.state_vrs)
        motion = chassis.partials(self.chassis_outputs, chassis.state_vrs)
        for corner in CORNERS:
            part, at = self.parts[corner], self.slices[corner]
            inputs, rows = self.corner_inputs[corner]
            unknowns = part.derivative_vrs + self.force_vr[corner]
            own = part.partials(unknowns, part.state_vrs)
            via = part.partials(unknowns, inputs) @ motion[rows]
            force = chassis.partials(chassis.derivative_vrs, [self.chassis_inputs[self.force_order.index(corner)]])
            jac[at, at] = own[:-1]
            jac[at, ch] = via[:-1]
            jac[ch, at] = force @ own[-1:]
            jac[ch, ch] += force @ via[-1:]
        return jac

    def free(self):
        for part in self.parts.values():
            part.free()


def run_model_exchange_car(ssp: Path, stop_time: float, rtol: float, overrides: dict | None = None):
    from scipy.integrate import DOP853

    work = Path(tempfile.mkdtemp())
    try:
        car = Car(ssp, work, overrides)
        solver = DOP853(car.derivatives, 0.0, car.state(), stop_time, rtol=rtol, atol=rtol * 1e-3)
        steps = 0
        while solver.status == "running":
            solver.step()
            car.complete(solver.t, solver.y)
            steps += 1
        assert solver.status == "finished", solver.message
        car.set_point(solver.t, solver.y)
        summary = {
            "chassis": {name: car.parts["chassis"].read(name) for name in CHASSIS},
            "corners": {c: {name: car.parts[c].read(name) for name in CORNER} for c in CORNERS},
        }
        lift_offs = {c: car.parts[c].read("lift_off_count") for c in CORNERS}
        car.free()
        return summary, lift_offs, steps
    finally:
        shutil.rmtree(work, ignore_errors=True)


CHASSIS = ["rms_heave_acceleration", "rms_pitch_acceleration", "rms_roll_acceleration"]
CORNER = ["rms_suspension_deflection", "rms_tire_deflection", "rms_dynamic_tire_load_ratio"]


def flat(summary):
    values = {("chassis", n): summary["chassis"][n] for n in CHASSIS}
    values.update({(c, n): summary["corners"][c][n] for c in CORNERS for n in CORNER})
    return values


def monolithic_car(fmu_file: Path, stop: float, flags: tuple = ("--road", "iso8608")) -> dict:
    """`tdvass car` with `flags`, by default on the SSD's road (the command
    line next to the FMUs: target/release/tdvass), in the summary's
    shape."""
    binary = fmu_file.parent.parent / "release" / ("tdvass.exe" if sys.platform == "win32" else "tdvass")
    if not binary.is_file():
        pytest.fail(f"{binary} not found; build it with `cargo build --release`")
    done = subprocess.run([str(binary), "car", *flags, "--duration", repr(stop), "--json"],
                          capture_output=True, text=True, check=True, timeout=300)
    car = json.loads(done.stdout)
    return {"chassis": {n: car[n] for n in CHASSIS},
            "corners": {c: {n: car["corners"][c][n] for n in CORNER} for c in CORNERS}}


def test_the_full_car_in_model_exchange_is_the_limit_of_its_co_simulation(fmu_file):
    """The five Model Exchange FMUs of full-car.ssp in one DOP853 solver
    (rtol 1e-8, CompletedIntegratorStep at every accepted step) over 0.5 s
    of the ISO 8608 class C road.

    Against the monolithic car (`tdvass car`, the same car as one delay
    equation): within 1e-5 of every RMS value (measured: 1.8e-6).

    Against the Co-Simulation car of examples/full_car.py at h = 0.1 ms and
    0.2 ms: the co-simulation's error is of second order in h (the SSD's
    `input_extrapolation = 1` continues the forces and the body's
    attachment over each communication step), so (CS(2h) - CS(h)) / 3
    estimates the error of CS(h) (Richardson): Model Exchange must lie
    within 0.5 times CS(2h) - CS(h), 1.5 times that estimate (plus 2e-6 of
    the value for its own solver), and within 1e-4 of CS(h). Measured: the
    chassis's RMS accelerations 1.4e-5 to 1.8e-5 of their value, 0.32 to
    0.35 times CS(2h) - CS(h); the corners' outputs 6e-8 to 4.6e-7, within
    the solver's allowance."""
    ssp = fmu_file.with_name("full-car.ssp")
    if not ssp.is_file():
        pytest.fail(f"{ssp} not found; build it with `cargo run --release -p fmu-build`")
    stop = 0.5
    me, lift_offs, _ = run_model_exchange_car(ssp, stop, 1e-8)
    # The bilateral tire of the SSD stays in contact: no event to handle.
    assert set(lift_offs.values()) == {0}
    exact = flat(monolithic_car(fmu_file, stop))
    for key, value in flat(me).items():
        assert abs(value - exact[key]) <= 1e-5 * abs(exact[key]), (key, value, exact[key])
    cs = {h: flat(full_car.run_car(ssp, stop, h)[2]) for h in (1e-4, 2e-4)}
    for key, value in flat(me).items():
        reference = cs[1e-4][key]
        richardson = abs(cs[2e-4][key] - reference)
        error = abs(value - reference)
        assert error <= 0.5 * richardson + 2e-6 * abs(value), (key, value, reference, richardson)
        assert error <= 1e-4 * abs(value), (key, value, reference)


def test_a_step_under_one_wheel_in_model_exchange_is_the_monolithic_car(fmu_file, tmp_path):
    """The SSD's car with a 2 cm step under the front left wheel from the
    start (every corner on the input road, `x_g` held: 0.02 m at fl, 0
    elsewhere), its five Model Exchange FMUs in one DOP853 solver at rtol
    1e-8 over 0.5 s, against `tdvass car` with each wheel on a road of its
    own (`--corner-road`): within 1e-5 of every RMS value (measured 1.4e-7).
    The mirror of the step rolls the car the other way: fl and fr swap."""
    ssp = fmu_file.with_name("full-car.ssp")
    if not ssp.is_file():
        pytest.fail(f"{ssp} not found; build it with `cargo run --release -p fmu-build`")
    stop = 0.5
    step = tmp_path / "step.csv"
    step.write_text("t,x_g\n0,0.02\n")

    def overrides(corner):
        return {c: {"road": 0, "road_delay": 0.0, "x_g": 0.02 if c == corner else 0.0} for c in CORNERS}

    runs = {}
    for corner, twin in (("fl", "fr"), ("fr", "fl")):
        me, lift_offs, _ = run_model_exchange_car(ssp, stop, 1e-8, overrides(corner))
        assert set(lift_offs.values()) == {0}
        exact = flat(monolithic_car(fmu_file, stop, ("--corner-road", f"{corner}=file:{step}")))
        for key, value in flat(me).items():
            assert abs(value - exact[key]) <= 1e-5 * abs(exact[key]), (corner, key, value, exact[key])
        deflection = {c: me["corners"][c]["rms_suspension_deflection"] for c in CORNERS}
        assert deflection[corner] > 5 * deflection[twin], deflection
        assert me["chassis"]["rms_roll_acceleration"] > 0.01
        runs[corner] = me
    for name in CORNER:
        left, right = runs["fl"]["corners"], runs["fr"]["corners"]
        assert left["fl"][name] == pytest.approx(right["fr"][name], rel=1e-6)
        assert left["rl"][name] == pytest.approx(right["rr"][name], rel=1e-6)


def test_the_assembled_car_s_jacobian_from_the_parts_partials_is_exact(fmu_file, tmp_path):
    """The car's Jacobian from the five FMUs' directional derivatives
    (`Car.jacobian`, the chain rule through the connections) against
    central differences of the whole system's derivatives, mid-run on the
    ISO road, each evaluated from the same saved FMU states."""
    ssp = fmu_file.with_name("full-car.ssp")
    if not ssp.is_file():
        pytest.fail(f"{ssp} not found; build it with `cargo run --release -p fmu-build`")
    from scipy.integrate import DOP853

    car = Car(ssp, tmp_path)
    solver = DOP853(car.derivatives, 0.0, car.state(), 0.05, rtol=1e-6, atol=1e-9)
    while solver.status == "running":
        solver.step()
        car.complete(solver.t, solver.y)
    t, y = solver.t, solver.y.copy()
    exact = car.jacobian(t, y)
    saved = {name: part.save() for name, part in car.parts.items()}
    def nominals_of(part):
        values = (part.buffer._type_ * part.n)()
        part.fmu.getNominalsOfContinuousStates(values, part.n)
        return np.array(values[:])

    nominals = np.concatenate([nominals_of(part) for part in car.parts.values()])

    def derivatives(z):
        for name, part in car.parts.items():
            part.restore(saved[name])
        return car.derivatives(t, z)

    scale = np.max(np.abs(exact), axis=1)
    for j in range(car.n):
        size = max(abs(y[j]), nominals[j])
        delta = 1e-4 * size
        up, down = y.copy(), y.copy()
        up[j] += delta
        down[j] -= delta
        f_up, f_down = derivatives(up), derivatives(down)
        difference = (f_up - f_down) / (2 * delta)
        # The differences' own rounding: a few ulp of the derivatives.
        rounding = 64 * np.finfo(float).eps * np.maximum(np.abs(f_up), np.abs(f_down)) / (2 * delta)
        bound = 1e-6 * np.maximum(np.maximum(np.abs(exact[:, j]), np.abs(difference)),
                                  1e-6 * scale * size) + rounding
        bad = np.nonzero(np.abs(exact[:, j] - difference) > bound)[0]
        assert bad.size == 0, [(i, j, exact[i, j], difference[i]) for i in bad]
    # The coupling is there: corners' rows see the chassis, and back.
    ch = car.slices["chassis"]
    assert np.count_nonzero(exact[car.slices[CORNERS[0]], ch]) > 0
    assert np.count_nonzero(exact[ch, car.slices[CORNERS[0]]]) > 0
    for name, part in car.parts.items():
        part.release(saved[name])
    car.free()
