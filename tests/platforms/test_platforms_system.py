"""The corner and the chassis, the full car's FMUs, on every platform: the
library they carry (the quarter car's, which the harnesses load; the GUID
or instantiationToken of their modelDescription.xml picks the model) runs
half a second at 1 ms steps in harness.c (FMI 2.0) and harness_fmi3.c (FMI
3.0) with inputs set before every step, as a master of the full car sets them: the
corner under a body moving 1 mm sin(2π 1.5 Hz t) (displacement and
velocity) on its default harmonic road, the chassis under four corner
forces, in FMI 2.0 also with the order-1 derivative of one of them
(conftest.py: DRIVEN_RUNS). Every output after every step is the same bits
on linux64, win64 (wine) and aarch64 (qemu)."""

import pytest
from conftest import DRIVEN_RUNS, DRIVEN_STEP, DRIVEN_STEPS, body_motion, corner_forces, force_fl_slope, model
from test_platforms import OTHER_PLATFORMS, compare

RUNS = sorted(DRIVEN_RUNS)


def column(table: tuple, vr: int) -> list[float]:
    header, rows = table
    return [row[header.index(str(vr))] for row in rows]


def variables(version: int, name: str) -> dict[str, int]:
    return model(DRIVEN_RUNS[(version, name)].fmu, version).variables


@pytest.mark.parametrize("platform", OTHER_PLATFORMS)
@pytest.mark.parametrize("version,name", RUNS, ids=[f"fmi{v}-{n}" for v, n in RUNS])
def test_driven_runs_agree_with_linux64(driven, version, name, platform):
    compare(f"fmi{version} {platform}" if version == 3 else platform, f"drive/{name}",
            driven(version, name, "linux64"), driven(version, name, platform))


def test_the_fmi3_corner_equals_the_fmi2_corner(driven):
    """One core, the same inputs: the same outputs (the same value
    references) under both FMI versions."""
    compare("fmi3 vs fmi2", "drive/corner", driven(2, "corner", "linux64"),
            driven(3, "corner", "linux64"))


def test_the_fmi3_chassis_equals_the_fmi2_chassis_without_derivatives(driven):
    compare("fmi3 vs fmi2", "drive/chassis", driven(2, "chassis_held", "linux64"),
            driven(3, "chassis", "linux64"))


@pytest.mark.parametrize("version,name", RUNS, ids=[f"fmi{v}-{n}" for v, n in RUNS])
def test_driven_runs_cover_half_a_second(driven, version, name):
    header, rows = driven(version, name, "linux64")
    assert len(rows) == DRIVEN_STEPS + 1
    assert rows[0][0] == 0.0 and rows[-1][0] == pytest.approx(DRIVEN_STEPS * DRIVEN_STEP, abs=1e-12)


@pytest.mark.parametrize("version", [2, 3])
def test_the_body_inputs_reach_the_corner(driven, version):
    """Over a step the body moves at body_velocity from body_displacement:
    after step k, suspension_deflection + x_t = x_b(t_k) + h v_b(t_k), so
    the comparisons above are of a corner that the inputs drive."""
    v = variables(version, "corner")
    table = driven(version, "corner", "linux64")
    sdd, x_t, force = column(table, v["suspension_deflection"]), column(table, v["x_t"]), column(table, v["body_force"])
    for k in range(DRIVEN_STEPS):
        u = body_motion(k * DRIVEN_STEP)
        body = u["body_displacement"] + DRIVEN_STEP * u["body_velocity"]
        assert sdd[k + 1] + x_t[k + 1] == pytest.approx(body, rel=1e-9, abs=1e-15), k
    assert max(force) - min(force) > 10.0  # N: the suspension pushes back on the moving body


@pytest.mark.parametrize("version,name", [(2, "chassis"), (2, "chassis_held"), (3, "chassis")])
def test_the_forces_reach_the_chassis(driven, version, name):
    """heave_acceleration after step k is the sum of the forces at the end
    of the step over the mass (1380 kg by default): held at their values at
    t_k, force_fl along its slope where the derivative is set."""
    v = variables(version, name)
    table = driven(version, name, "linux64")
    acceleration = column(table, v["heave_acceleration"])
    sloped = DRIVEN_RUNS[(version, name)].derivatives is not None
    for k in range(DRIVEN_STEPS):
        t = k * DRIVEN_STEP
        total = sum(corner_forces(t).values()) + (DRIVEN_STEP * force_fl_slope(t)["force_fl"] if sloped else 0.0)
        assert acceleration[k + 1] == pytest.approx(total / 1380.0, rel=1e-9, abs=1e-12), k
    for output in ["heave", "pitch", "roll"]:
        assert max(abs(x) for x in column(table, v[output])) > 1e-5, output


def test_the_input_derivative_changes_the_chassis_run(driven):
    v = variables(2, "chassis")
    sloped = column(driven(2, "chassis", "linux64"), v["heave"])
    held = column(driven(2, "chassis_held", "linux64"), v["heave"])
    assert sloped[0] == held[0] and sloped[1:] != held[1:]
