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
- The scheme is first order in the step: the difference between the runs
  at h and h/2 halves with h. Against the car without coupling error,
  `tdvass car` (the same car as one delay equation), 1 ms comes within
  1 % and 0.1 ms within 0.1 %, with the same lift-offs; the Richardson
  extrapolation of the runs at 0.125 ms and 62.5 us meets it within 1e-5.
- ECCO (libcosim's energy-conserving adaptive step over the four power
  bonds force x velocity) comes within 1 % too.
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
    """`car(master, step)`: the summary of one run, memoized."""
    directory = fmu_dir()
    for needed in ["full-car.ssp", "full-car/OspSystemStructure.xml", "full-car/OspSystemStructure_ecco.xml"]:
        if not (directory / needed).is_file():
            pytest.fail(f"{directory / needed} not found; build it with `cargo run --release -p fmu-build`")
    out = tmp_path_factory.mktemp("full-car")
    cache = {}

    def run(master: str, step: float = 1e-3) -> dict:
        key = (master, step)
        if key not in cache:
            path = out / f"{master}-{step}.json"
            done = subprocess.run(
                [sys.executable, str(HERE / "full_car.py"), master, str(directory), str(STOP_TIME), repr(step), str(path)],
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


def worst_relative(a: dict, b: dict) -> tuple[float, str]:
    va, vb = values(a), values(b)
    assert va.keys() == vb.keys()
    return max((abs(va[k] - vb[k]) / abs(vb[k]), k) for k in va)


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


def test_the_coupling_error_is_first_order_in_the_step(car):
    coarse, middle, fine = (car("libcosim-ssp", h) for h in (1e-3, 5e-4, 2.5e-4))
    first, _ = worst_relative(coarse, middle)
    second, _ = worst_relative(middle, fine)
    assert first < 0.05, first
    # Halving the step halves the difference (first order), give or take.
    assert 1.5 < first / second < 3.0, (first, second)


def extrapolated(car) -> dict:
    """The car without coupling error, as far as two fine runs tell: the
    Richardson extrapolation 2 r(h/2) - r(h) of the first-order scheme at
    h = 0.125 ms."""
    h, half = values(car("libcosim-ssp", 1.25e-4)), values(car("libcosim-ssp", 6.25e-5))
    limit = {k: 2.0 * half[k] - h[k] for k in h}
    chassis = {k[len("chassis."):]: v for k, v in limit.items() if k.startswith("chassis.")}
    corners = {}
    for k, v in limit.items():
        if not k.startswith("chassis."):
            corner, name = k.split(".", 1)
            corners.setdefault(corner, {})[name] = v
    return {"chassis": chassis, "corners": corners}


@pytest.mark.parametrize("step, within", [(1e-3, 1e-2), (1e-4, 1e-3)])
def test_the_fixed_step_comes_within_its_bound_of_the_monolithic_car(car, step, within):
    run = car("libcosim-ssp", step)
    worst, where = worst_relative(run, car("monolithic"))
    assert worst < within, (step, worst, where)
    # The lift-offs are counted alike.
    assert counts(run) == counts(car("monolithic"))


def test_the_extrapolated_co_simulation_is_the_monolithic_car(car):
    # Two independent ways to the car without coupling error meet.
    worst, where = worst_relative(extrapolated(car), car("monolithic"))
    assert worst < 1e-5, (worst, where)


def test_ecco_stays_within_one_percent(car):
    ecco = car("libcosim-ecco")
    assert ecco["time"] >= STOP_TIME - 1e-9
    worst, where = worst_relative(ecco, car("monolithic"))
    assert worst < 0.01, (worst, where)
    assert abs(sum(counts(ecco).values()) - sum(counts(car("monolithic")).values())) <= 1
