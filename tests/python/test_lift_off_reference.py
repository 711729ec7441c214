"""The unilateral tire against an independent event-located reference:
scipy's DOP853 at rtol 1e-12 with an event at every lift-off and touchdown
(`lift_off_reference.py`, the quarter car written out there), for CS and
PVASS, on a harmonic road near wheel hop and on an ISO 8608 class E road
given as samples. `tdvass simulate --tire-contact unilateral` at tolerance
1e-9 must give RMS BA, SDD, TDD to 1e-7 relative, the flight time to 1e-9 s
and the same number of lift-offs."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from lift_off_reference import iso8608_samples, reference

ROOT = Path(__file__).resolve().parents[2]
DURATION = 3.0
CLASS_E = 4096e-6  # Gq(n0) of class E (m^3)


def tdvass_binary() -> str:
    binary = os.environ.get("TDVASS_BIN")
    if binary:
        return binary
    cargo = shutil.which("cargo")
    if cargo is None:
        pytest.fail("cargo not found and TDVASS_BIN not set")
    subprocess.run([cargo, "build", "--quiet", "--release", "--bin", "tdvass"], cwd=ROOT, check=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return str(target / "release" / "tdvass")


def simulate(variant, road_args):
    done = subprocess.run(
        [tdvass_binary(), "simulate", "--json", "--tire-contact", "unilateral",
         "--variant", variant, "--duration", str(DURATION), "--tolerance", "1e-9", *road_args],
        capture_output=True, text=True, check=True)
    return json.loads(done.stdout)


def compare(result, expected, label):
    assert result["tire_contact"] == "unilateral"
    assert expected["lift_off_count"] >= 5, f"{label}: the case must lift off: {expected}"
    assert result["lift_off_count"] == expected["lift_off_count"], label
    for name in ("rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection"):
        key = {"rms_body_acceleration": "rms_ba", "rms_suspension_deflection": "rms_sdd",
               "rms_tire_deflection": "rms_tdd"}[name]
        error = abs(result[name] - expected[key]) / expected[key]
        assert error < 1e-7, f"{label}: {name} {result[name]} against {expected[key]} ({error:.1e})"
    error = abs(result["contact_loss_time"] - expected["contact_loss_time"])
    assert error < 1e-9, f"{label}: flight time off by {error:.1e} s"


@pytest.mark.parametrize("variant", ["cs", "pvass"])
def test_harmonic_road_near_wheel_hop(variant):
    amplitude, omega = 0.02, 60.0
    expected = reference(variant, lambda t: amplitude * np.sin(omega * t), DURATION)
    result = simulate(variant, ["--road", "harmonic", "--road-amplitude", str(amplitude),
                                "--road-angular-frequency", str(omega)])
    compare(result, expected, f"{variant}, harmonic")


@pytest.mark.parametrize("variant", ["cs", "pvass"])
def test_iso8608_class_e_road(variant, tmp_path):
    t, x = iso8608_samples(CLASS_E, 20.0, DURATION + 0.1, 0.01, seed=7)
    path = tmp_path / "class_e.csv"
    np.savetxt(path, np.column_stack([t, x]), delimiter=",", fmt="%.17g")
    expected = reference(variant, lambda s: np.interp(s, t, x), DURATION, breakpoints=t)
    result = simulate(variant, ["--road", f"file:{path}"])
    compare(result, expected, f"{variant}, class E")
