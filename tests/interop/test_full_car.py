"""The assembled car (full-car.ssp and full-car/OspSystemStructure*.xml:
the chassis FMU on four corner FMUs, each corner on the ISO 8608 road, the
rear ones a wheelbase behind, the right track on a road of its own) in
libcosim (fixed step from the OSP structure and from the SSP, and ECCO),
ecos (from the SSP) and a plain fmpy loop (tests/interop/full_car.py).

What is compared, over the first STOP_TIME seconds: the chassis's RMS
heave, pitch and roll accelerations, the seat's W_k-weighted RMS
acceleration and VDV, and each corner's RMS suspension deflection, tire
deflection and dynamic tire load ratio, and its lift-off count.

- The three fixed-step masters run the same Jacobi scheme at 1 ms, so they
  agree to the rounding of their clocks (libcosim counts integer
  nanoseconds, ecos sums the step, the fmpy loop multiplies it).
- The SSD sets `input_extrapolation = 1` on every FMU: the corners
  continue the body's attachment, the chassis the forces, from their last
  two values over a step. The scheme is then second order in the step:
  the difference between the runs at h and h/2 falls four times. Against
  the car without coupling error, `tdvass car` (the same car as one delay
  equation), 1 ms comes within 0.4 % and 0.1 ms within 0.004 %, with the
  same lift-offs; the Richardson extrapolation of the runs at 0.125 ms and
  62.5 us meets it within 2e-6.
- Holding the inputs instead (the FMI default, scenario `hold`) is first
  order, and at 1 ms more than twice as far from the car.
- ECCO (libcosim's energy-conserving adaptive step over the four power
  bonds force x velocity) comes within 0.5 %.
- The same on a sedan whose front and rear do not decouple (full_car.py's
  scenarios `sedan-c`, class C with the same road under both tracks,
  `sedan-e`, class E at 30 m/s with the tire that cannot pull, and
  `sedan-step`, a 2 cm step under the front left wheel only): every
  master sets the scenario's parameters through its own API (`SEDANS`),
  and the lift-off counts agree within one.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import interop

HERE = Path(__file__).resolve().parent
STOP_TIME = 2.0


def fmu_dir() -> Path:
    return interop.fmu_path().parent


@pytest.fixture(scope="module")
def car(tmp_path_factory):
    """`car(master, step, scenario)`: the summary of one run, memoized."""
    directory = fmu_dir()
    for needed in ["full-car.ssp", "full-car/OspSystemStructure.xml", "full-car/OspSystemStructure_ecco.xml"]:
        if not (directory / needed).is_file():
            pytest.fail(f"{directory / needed} not found; build it with `cargo run --release -p fmu-build`")
    out = tmp_path_factory.mktemp("full-car")
    cache = {}

    def run(master: str, step: float = 1e-3, scenario: str | None = None) -> dict:
        key = (master, step, scenario)
        if key not in cache:
            path = out / f"{master}-{step}-{scenario or 'ssd'}.json"
            done = subprocess.run(
                [sys.executable, str(HERE / "full_car.py"), master, str(directory), str(STOP_TIME), repr(step), str(path),
                 *([scenario] if scenario else [])],
                capture_output=True,
                text=True,
                timeout=600,
            )
            assert done.returncode == 0, f"{master} failed ({done.returncode})\n{done.stdout}\n{done.stderr}"
            cache[key] = json.loads(path.read_text())
        return cache[key]

    return run


def values(summary: dict) -> dict:
    """Every real value of a summary by a flat name; the counts apart."""
    flat = {f"chassis.{k}": v for k, v in summary["chassis"].items()}
    for corner, outputs in summary["corners"].items():
        flat.update({f"{corner}.{k}": v for k, v in outputs.items() if k != "lift_off_count"})
    return flat


def counts(summary: dict) -> dict:
    return {corner: outputs["lift_off_count"] for corner, outputs in summary["corners"].items()}


# Below this a value is a rounding of zero (the roll of a car with the same
# road under both tracks: exactly 0 in the co-simulations, 1e-15 in
# `tdvass car`); such values are compared absolutely.
ZERO = 1e-9


def worst_relative(a: dict, b: dict) -> tuple[float, str]:
    """The largest relative difference of a's values from b's."""
    va, vb = values(a), values(b)
    assert va.keys() == vb.keys()
    zeros = [k for k in vb if abs(vb[k]) < ZERO]
    assert all(abs(va[k]) < ZERO for k in zeros), {k: (va[k], vb[k]) for k in zeros}
    return max((abs(va[k] - vb[k]) / abs(vb[k]), k) for k in va if k not in zeros)


def test_the_car_moves_in_heave_pitch_and_roll(car):
    s = car("libcosim-osp")
    assert s["time"] == pytest.approx(STOP_TIME, abs=1e-9)
    for name, value in s["chassis"].items():
        assert 0.0 < value < 100.0, (name, value)
    # Four different roads under the four wheels: four different corners.
    deflections = [s["corners"][c]["rms_suspension_deflection"] for c in ["fl", "fr", "rl", "rr"]]
    assert len(set(deflections)) == 4, deflections


@pytest.mark.parametrize("master", ["fmpy-loop", "libcosim-ssp", "ecos-ssp"])
def test_the_fixed_step_masters_agree_with_libcosim(car, master):
    reference = car("libcosim-osp")
    other = car(master)
    worst, where = worst_relative(other, reference)
    # Their clocks differ by roundings only.
    assert worst <= 1e-9, (master, worst, where)
    assert counts(other) == counts(reference)


def test_the_coupling_error_is_second_order_in_the_step(car):
    coarse, middle, fine = (car("libcosim-ssp", h) for h in (1e-3, 5e-4, 2.5e-4))
    first, _ = worst_relative(coarse, middle)
    second, _ = worst_relative(middle, fine)
    assert first < 0.01, first
    # Halving the step quarters the difference (second order): measured
    # 1.41e-3 then 3.52e-4.
    assert 3.5 < first / second < 4.5, (first, second)


def test_holding_the_inputs_is_first_order_and_farther_from_the_car(car):
    exact = car("monolithic")
    coarse, fine = (worst_relative(car("libcosim-ssp", h, "hold"), exact)[0] for h in (1e-3, 5e-4))
    # Measured: 5.1e-3 and 2.6e-3 (halving the step halves the error).
    assert coarse < 0.01, coarse
    assert 1.5 < coarse / fine < 2.5, (coarse, fine)
    extrapolated_run, _ = worst_relative(car("libcosim-ssp", 1e-3), exact)
    # Measured: 1.9e-3, 2.7 times closer.
    assert extrapolated_run < coarse / 2.0, (extrapolated_run, coarse)


def extrapolated(car) -> dict:
    """The car without coupling error, as far as two fine runs tell: the
    Richardson extrapolation (4 r(h/2) - r(h)) / 3 of the second-order
    scheme at h = 0.125 ms."""
    h, half = values(car("libcosim-ssp", 1.25e-4)), values(car("libcosim-ssp", 6.25e-5))
    limit = {k: (4.0 * half[k] - h[k]) / 3.0 for k in h}
    chassis = {k[len("chassis."):]: v for k, v in limit.items() if k.startswith("chassis.")}
    corners = {}
    for k, v in limit.items():
        if not k.startswith("chassis."):
            corner, name = k.split(".", 1)
            corners.setdefault(corner, {})[name] = v
    return {"chassis": chassis, "corners": corners}


# Measured: 1.9e-3 at 1 ms, 1.9e-5 at 0.1 ms (the chassis's RMS pitch
# acceleration).
@pytest.mark.parametrize("step, within", [(1e-3, 4e-3), (1e-4, 4e-5)])
def test_the_fixed_step_comes_within_its_bound_of_the_monolithic_car(car, step, within):
    run = car("libcosim-ssp", step)
    worst, where = worst_relative(run, car("monolithic"))
    assert worst < within, (step, worst, where)
    # The lift-offs are counted alike.
    assert counts(run) == counts(car("monolithic"))


def test_the_extrapolated_co_simulation_is_the_monolithic_car(car):
    # Two independent ways to the car without coupling error meet:
    # measured 4.2e-7.
    worst, where = worst_relative(extrapolated(car), car("monolithic"))
    assert worst < 2e-6, (worst, where)


def test_ecco_stays_within_one_percent(car):
    ecco = car("libcosim-ecco")
    assert ecco["time"] >= STOP_TIME - 1e-9
    worst, where = worst_relative(ecco, car("monolithic"))
    # Measured: 1.0e-4.
    assert worst < 5e-3, (worst, where)
    assert abs(sum(counts(ecco).values()) - sum(counts(car("monolithic")).values())) <= 1


# ------------------------------------------------------------------ the sedan
#
# The SSD's car has the default chassis, whose front and rear decouple (the
# centre of gravity midway, pitch inertia m a b). The scenarios of
# full_car.py put a sedan on the corners whose front and rear are coupled:
# a = 1.2 m, b = 1.4 m, pitch inertia 0.9 m a b (dynamic index 0.9), each
# corner's static load its share of the body's weight, the rear wheels a
# wheelbase behind at the scenario's speed.
#
# Each scenario: the bounds on the largest relative difference from
# `tdvass car` of libcosim's fixed step at 1 ms and at 0.1 ms (the issue's
# are 1 % and 0.1 %).
SEDANS = {
    # The same class C road under both tracks at 20 m/s, linear tire.
    # Measured: 1.86e-3 at 1 ms, 1.85e-5 at 0.1 ms.
    "sedan-c": (5e-3, 5e-5),
    # Class E at 30 m/s, a road of its own under each track, the tire that
    # cannot pull: each wheel lifts off 40 to 45 times in the 2 s. Measured:
    # 1.46e-3 at 1 ms and 1.47e-5 at 0.1 ms (the chassis's RMS heave
    # acceleration).
    "sedan-e": (5e-3, 5e-5),
    # A 2 cm step under the front left wheel only, at the start, the linear
    # tire: the car heaves, pitches and rolls and settles. Measured: 1.74e-3
    # at 1 ms and 1.72e-5 at 0.1 ms (the chassis's RMS heave acceleration).
    "sedan-step": (5e-3, 5e-5),
}


def assert_counts_within_one(run: dict, reference: dict):
    """Each corner's lift-off count within 1 of the reference's."""
    got, want = counts(run), counts(reference)
    assert all(abs(got[c] - want[c]) <= 1 for c in want), (got, want)


def test_the_sedan_runs_the_scenario(car):
    # The scenario's parameters reached every master (full_car.py reads
    # them back in libcosim and ecos); here, what they do.
    symmetric = car("libcosim-osp", scenario="sedan-c")
    assert symmetric["chassis"]["rms_roll_acceleration"] == 0.0
    corners = symmetric["corners"]
    assert corners["fl"] == corners["fr"] and corners["rl"] == corners["rr"]
    assert corners["fl"] != corners["rl"]
    rough = car("libcosim-osp", scenario="sedan-e")
    assert rough["chassis"]["rms_roll_acceleration"] > 0.1
    assert all(n >= 10 for n in counts(rough).values()), counts(rough)
    # The SSD's car is not the sedan.
    assert worst_relative(symmetric, car("libcosim-osp"))[0] > 0.01
    # The step under the front left wheel rolls the car, and that corner
    # works hardest: its suspension deflects more than ten times as much
    # as any other's. No wheel lifts off.
    step = car("libcosim-osp", scenario="sedan-step")
    assert step["chassis"]["rms_roll_acceleration"] > 0.1
    deflection = {c: outputs["rms_suspension_deflection"] for c, outputs in step["corners"].items()}
    assert all(deflection["fl"] > 10.0 * deflection[c] for c in ["fr", "rl", "rr"]), deflection
    assert set(counts(step).values()) == {0}


@pytest.mark.parametrize("scenario", sorted(SEDANS))
@pytest.mark.parametrize("master", ["fmpy-loop", "libcosim-ssp", "ecos-ssp"])
def test_the_fixed_step_masters_agree_with_libcosim_on_the_sedan(car, scenario, master):
    reference = car("libcosim-osp", scenario=scenario)
    other = car(master, scenario=scenario)
    worst, where = worst_relative(other, reference)
    assert worst <= 1e-9, (master, worst, where)
    assert counts(other) == counts(reference)


@pytest.mark.parametrize("scenario", sorted(SEDANS))
def test_the_sedan_fixed_step_comes_within_its_bound_of_the_monolithic_car(car, scenario):
    exact = car("monolithic", scenario=scenario)
    coarse, fine = (car("libcosim-ssp", h, scenario) for h in (1e-3, 1e-4))
    (coarse_bound, fine_bound) = SEDANS[scenario]
    first, where_first = worst_relative(coarse, exact)
    second, where_second = worst_relative(fine, exact)
    assert first < coarse_bound, (first, where_first)
    assert second < fine_bound, (second, where_second)
    # A tenth of the step, a hundredth of the error (second order): the
    # largest difference falls 99 to 101 times.
    assert first / second > 80.0, (first, second)
    assert_counts_within_one(coarse, exact)
    assert_counts_within_one(fine, exact)


@pytest.mark.parametrize("scenario", sorted(SEDANS))
def test_ecco_stays_within_one_percent_on_the_sedan(car, scenario):
    ecco = car("libcosim-ecco", scenario=scenario)
    # libcosim ends an adaptive run once less than 1 % of a step is left.
    assert ecco["time"] >= STOP_TIME - 1e-4
    # Measured: 6.1e-5 (sedan-c), 1.08e-4 (sedan-e), 9.3e-4 (sedan-step).
    worst, where = worst_relative(ecco, car("monolithic", scenario=scenario))
    assert worst < 5e-3, (worst, where)
    assert_counts_within_one(ecco, car("monolithic", scenario=scenario))
