"""Model Exchange under other masters' habits, both FMI versions: explicit
Runge–Kutta loops at a fixed step that call CompletedIntegratorStep at every
step or never (the convergence order against the exact co-simulation),
scipy's implicit solvers with and without the FMU's Jacobian, and the
directional derivatives against central differences of the derivatives and
outputs. The long sweeps are in benches/model_exchange_masters.py."""

from __future__ import annotations

import fmpy
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from me_master import HEUN, RK4, ModelExchangeMaster, explicit
from test_model_exchange import AVERAGES, FMUS


@pytest.fixture(scope="module")
def unzipped(tmp_path_factory):
    return {v: fmpy.extract(str(f), unzipdir=str(tmp_path_factory.mktemp(v))) for v, f in FMUS.items()}


def exact(start, duration, version="fmi2"):
    """The co-simulation's time averages at `duration`, at the tightest
    tolerance."""
    result = fmpy.simulate_fmu(str(FMUS[version]), fmi_type="CoSimulation", start_values=start,
                               stop_time=duration, relative_tolerance=1e-12, output_interval=duration,
                               output=AVERAGES)
    return np.array([result[k][-1] for k in AVERAGES])


def averages(master):
    return np.array([master.read(k) for k in AVERAGES])


def largest_error(values, reference):
    return float(np.max(np.abs(values / reference - 1)))


def errors_of(version, unzipped, start, duration, method, steps, complete):
    reference = exact(start, duration, version)
    errors = []
    for h in steps:
        master = ModelExchangeMaster(FMUS[version], start, unzipped[version])
        explicit(master, method, duration, h, complete)
        errors.append(largest_error(averages(master), reference))
        master.free()
    return errors


# ------------------------------------------------ explicit Runge–Kutta masters


@pytest.mark.parametrize("version", FMUS)
@pytest.mark.parametrize("tau, steps", [(0.011, [1e-3, 5e-4, 2.5e-4]), (2e-4, [1e-4, 5e-5, 2.5e-5])],
                         ids=["tau-11ms", "tau-0.2ms"])
def test_rk4_completing_its_steps_converges_at_fourth_order(version, unzipped, tau, steps):
    errors = errors_of(version, unzipped, {"variant": 3, "tau": tau}, 0.5, RK4, steps, complete=True)
    ratios = [a / b for a, b in zip(errors, errors[1:])]
    assert all(r >= 11 for r in ratios), (errors, ratios)


def test_heun_completing_its_steps_converges_at_second_order(unzipped):
    # Below 3e-5 s: at longer steps a higher-order term of Heun's own error
    # changes the sign of some averages' errors (so without a delay too).
    errors = errors_of("fmi2", unzipped, {"variant": 3, "tau": 0.011}, 0.25, HEUN, [1.5625e-5, 7.8125e-6],
                       complete=True)
    assert errors[0] / errors[1] >= 3.4, errors


@pytest.mark.parametrize("version", FMUS)
def test_rk4_that_never_completes_a_step_stays_within_1e_5(version, unzipped):
    errors = errors_of(version, unzipped, {"variant": 3, "tau": 0.011}, 1.0, RK4, [1e-3], complete=False)
    assert errors[0] < 1e-5, errors


# ------------------------------------------------------------ scipy's solvers


def scipy_run(version, unzipped, start, duration, method, rtol, with_jacobian):
    master = ModelExchangeMaster(FMUS[version], start, unzipped[version])
    nominals = np.ones(master.n)
    master.fmu.getNominalsOfContinuousStates(master.buffer, master.n)
    nominals[:] = master.buffer[:]
    solution = solve_ivp(master.derivatives, (0.0, duration), master.states(), method=method, rtol=rtol,
                         atol=rtol * nominals, jac=master.jacobian if with_jacobian else None)
    assert solution.success, solution.message
    master.set_point(duration, solution.y[:, -1])
    values = averages(master)
    master.free()
    return values


@pytest.mark.parametrize("version", FMUS)
@pytest.mark.parametrize("method", ["Radau", "BDF"])
@pytest.mark.parametrize("with_jacobian", [True, False], ids=["fmu-jacobian", "scipy-differences"])
def test_scipy_implicit_solvers_agree_with_the_cosimulation(version, unzipped, method, with_jacobian):
    start = {"variant": 3, "tau": 0.011, "road_angular_frequency": 2.0}
    duration, rtol = 3.0, 1e-6
    values = scipy_run(version, unzipped, start, duration, method, rtol, with_jacobian)
    assert largest_error(values, exact(start, duration, version)) < 100 * rtol


@pytest.mark.parametrize("method", ["Radau", "BDF"])
def test_scipy_on_a_random_road_with_the_fmu_jacobian(unzipped, method):
    start = {"variant": 3, "tau": 0.011, "road": 2, "road_class": 3, "vehicle_speed": 20.0}
    duration, rtol = 0.5, 1e-4
    values = scipy_run("fmi2", unzipped, start, duration, method, rtol, True)
    assert largest_error(values, exact(start, duration)) < 100 * rtol


# ------------------------------------------------------ directional derivatives


def output_vrs(master):
    return [v.valueReference for v in master.md.modelVariables
            if v.causality == "output" and v.type in ("Real", "Float64")]


def check_partials(master, road_input=None, inputs=()):
    """The FMU's partials of the derivatives and the Real outputs at the
    master's point against central differences of GetDerivatives and
    GetReal, each evaluated from the same saved FMU state (so the delay
    history is the same for every evaluation). The knowns are the states,
    `x_g` when `road_input` = (its value reference, its value) is given,
    and the inputs named in `inputs` ((name, value) pairs, set at those
    values)."""
    inputs = ([("x_g", road_input[1])] if road_input else []) + list(inputs)
    for name, value in inputs:
        master.set(name, value)
    t, x = master.t, master.x.copy()
    master.set_point(t, x)
    knowns = list(master.state_vrs) + [master.by_name[name].valueReference for name, _ in inputs]
    unknowns = list(master.derivative_vrs) + output_vrs(master)
    saved = master.save()
    exact_matrix = master.partials(unknowns, knowns)
    nominals = (master.buffer._type_ * master.n)()
    master.fmu.getNominalsOfContinuousStates(nominals, master.n)

    def evaluate(j, delta):
        # The outputs first: the derivatives record the point, and a
        # point recorded at t can change the history the outputs at t read.
        y = x.copy()
        if j < master.n:
            y[j] += delta
        values = []
        for read in (lambda: (master.fmu.getFloat64 if master.fmi3 else master.fmu.getReal)(output_vrs(master)),
                     lambda: master.derivatives(t, y)):
            master.restore(saved)
            if j >= master.n:
                name, value = inputs[j - master.n]
                master.set(name, value + delta)
            master.set_point(t, y)
            values.append(np.asarray(read()))
        return np.concatenate([values[1], values[0]])

    for j in range(len(knowns)):
        size = max(abs(x[j]), nominals[j]) if j < master.n else max(abs(inputs[j - master.n][1]), 1e-3)
        # Most partials are of functions linear in the known: a step far
        # above the rounding of the values (1e-4) costs nothing there.
        delta = 1e-4 * size
        difference = (evaluate(j, delta) - evaluate(j, -delta)) / (2 * delta)
        column = exact_matrix[:, j]
        scale = np.max(np.abs(exact_matrix), axis=1) * size
        bound = 1e-6 * np.maximum(np.maximum(np.abs(column), np.abs(difference)), 1e-6 * scale)
        bad = np.nonzero(np.abs(column - difference) > bound)[0]
        assert bad.size == 0, [(unknowns[i], knowns[j], column[i], difference[i]) for i in bad]
    master.restore(saved)
    master.release(saved)
    return exact_matrix


@pytest.mark.parametrize("version", FMUS)
@pytest.mark.parametrize("tau", [0.0, 2e-4, 0.011])
def test_directional_derivatives_agree_with_central_differences(version, unzipped, tau):
    master = ModelExchangeMaster(FMUS[version], {"variant": 3, "tau": tau}, unzipped[version])
    explicit(master, RK4, 0.3, 1e-3, complete=False)
    # A stage inside the next step: with tau = 2e-4 the delayed value
    # interpolates towards the current state.
    master.t += 7e-4
    matrix = check_partials(master)
    if version == "fmi3":
        # The adjoint derivative is the transpose.
        seed = np.arange(1.0, master.n + 1)
        adjoint = master.fmu.getAdjointDerivative(master.derivative_vrs, master.state_vrs, list(seed),
                                                  master.n)
        assert np.allclose(adjoint, matrix[: master.n, : master.n].T @ seed, rtol=1e-12, atol=0.0)
    master.free()


@pytest.mark.parametrize("version", FMUS)
def test_directional_derivatives_in_flight_and_with_the_road_input(version, unzipped):
    start = {"variant": 3, "tau": 2e-4, "road": 0, "tire_contact": 1}
    master = ModelExchangeMaster(FMUS[version], start, unzipped[version])
    master.set("x_g", 0.01)
    explicit(master, RK4, 0.3, 1e-3, complete=False)
    x_g = master.by_name["x_g"].valueReference
    check_partials(master, road_input=(x_g, 0.01))
    # Lift the wheel off the road: an event, then flight.
    x = master.x.copy()
    limit = 0.01 + 2 * (345 + 4.05 + 40.5) * 9.80665 / 190000
    x[4], x[5] = limit, 0.3
    # The derivatives jump at the switch: the master is told to restart.
    assert master.event(master.t, x)
    assert master.read("lift_off_count") >= 1
    # An event that switches nothing does not ask for it.
    assert not master.event(master.t, x)
    master.t, master.x = master.t + 3e-4, x
    x[0] += 0.1 * (x[4] - x[0])  # off the largest |SDD| the event recorded
    check_partials(master, road_input=(x_g, 0.01))
    master.free()


@pytest.mark.parametrize("which", ["fmi2", "fmi3"])
@pytest.mark.parametrize("start", [{"variant": 3, "tau": 2e-4, "road": 0, "tire_contact": 1},
                                   {"variant": 2}, {"variant": 3, "tau": 0.011}],
                         ids=["tdvass-unilateral-x_g", "pvass", "tdvass-11ms"])
def test_the_corner_s_directional_derivatives_agree_with_central_differences(which, start, corner_file,
                                                                           corner_fmi3_file):
    """The corner's partials of its 7 derivatives and its Real outputs
    (`body_force` among them) with respect to its states and its inputs:
    the body attachment, and x_g where the road is the input."""
    fmu = corner_file if which == "fmi2" else corner_fmi3_file
    master = ModelExchangeMaster(fmu, start, fmpy.extract(str(fmu)))
    inputs = [("body_displacement", 0.004), ("body_velocity", -0.03)]
    if start.get("road") == 0:
        inputs.append(("x_g", 0.01))
    for name, value in inputs:
        master.set(name, value)
    explicit(master, RK4, 0.3, 1e-3, complete=False)
    master.t += 7e-4
    matrix = check_partials(master, inputs=inputs)
    forces = [i for i, vr in enumerate(output_vrs(master)) if vr == master.by_name["body_force"].valueReference]
    row = matrix[master.n + forces[0]]
    # The force moves with the attachment (the suspension's spring and damper).
    assert row[master.n] < 0 and row[master.n + 1] < 0, row
    if master.fmi3:
        seed = np.arange(1.0, master.n + 1)
        adjoint = master.fmu.getAdjointDerivative(master.derivative_vrs, master.state_vrs, list(seed), master.n)
        assert np.allclose(adjoint, matrix[: master.n, : master.n].T @ seed, rtol=1e-12, atol=0.0)
    master.free()
