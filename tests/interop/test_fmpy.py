"""fmpy, the reference master: its validator, simulate_fmu and its CLI."""

import subprocess
import sys
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.util import read_csv
from fmpy.validation import validate_fmu

import interop
from interop import EXPERIMENTS, OUTPUTS

# The console script, as a user types it.
FMPY = [str(Path(sys.executable).parent / "fmpy")]


def test_validate_fmu_finds_nothing(fmu_file):
    assert validate_fmu(str(fmu_file)) == []
    interop.record(f"fmpy {fmpy.__version__}", "-", "validate_fmu", "no problems")


def test_cli_info(fmu_file):
    done = subprocess.run(FMPY + ["info", str(fmu_file)], capture_output=True, text=True, check=True)
    assert "TDVASS" in done.stdout and "Co-Simulation" in done.stdout
    assert "FMI Version        2.0" in done.stdout


def test_cli_validate(fmu_file):
    done = subprocess.run(FMPY + ["validate", str(fmu_file)], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr  # exit code = number of problems
    assert "No problems found" in done.stdout, done.stdout
    interop.record(f"fmpy CLI {fmpy.__version__}", "-", "fmpy validate", "no problems")


def test_cli_validate_and_info_of_the_corner(corner_file):
    done = subprocess.run(FMPY + ["validate", str(corner_file)], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "No problems found" in done.stdout, done.stdout
    info = subprocess.run(FMPY + ["info", str(corner_file)], capture_output=True, text=True, check=True).stdout
    version = interop.CORNER_FMUS[corner_file.name]
    assert "TDVASS corner" in info, info
    assert "\n  FMI Type           Model Exchange, Co-Simulation\n" in info, info  # both interfaces
    assert f"FMI Version        {version}" in info, info
    interop.record(f"fmpy CLI {fmpy.__version__}", f"corner {version}", "fmpy validate", "no problems")


def test_cli_validate_and_info_of_the_chassis(chassis_file):
    done = subprocess.run(FMPY + ["validate", str(chassis_file)], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "No problems found" in done.stdout, done.stdout
    info = subprocess.run(FMPY + ["info", str(chassis_file)], capture_output=True, text=True, check=True).stdout
    version = interop.CHASSIS_FMUS[chassis_file.name]
    assert "TDVASS chassis" in info, info
    assert "\n  FMI Type           Model Exchange, Co-Simulation\n" in info, info  # both interfaces
    assert f"FMI Version        {version}" in info, info
    for name in ["force_fl", "force_rr", "displacement_fl", "heave", "roll_rate", "seat_acceleration"]:
        assert name in info, (name, info)
    interop.record(f"fmpy CLI {fmpy.__version__}", f"chassis {version}", "fmpy validate", "no problems")


@pytest.mark.parametrize("name", list(EXPERIMENTS))
def test_simulate_fmu_equals_a_replay_on_its_grid(fmu_file, fmpy_reference, replay, name):
    # simulate_fmu (its own loop, recorder and, for the input road, its input
    # table) against the plain FMU2Slave loop on the same times.
    times, rows = fmpy_reference(name)
    np.testing.assert_array_equal(times, interop.fmpy_grid(EXPERIMENTS[name].stop_time))
    result = interop.assert_agrees(rows, replay(name, times), what=f"fmpy {name}")
    interop.record(f"fmpy {fmpy.__version__}", name, "FMU2Slave replay", result, "simulate_fmu")


@pytest.mark.parametrize("name", list(EXPERIMENTS))
def test_cli_simulate(fmu_file, fmpy_reference, tmp_path, name):
    experiment = EXPERIMENTS[name]
    command = FMPY + [
        "simulate", str(fmu_file),
        "--interface-type", "CoSimulation",
        "--stop-time", repr(experiment.stop_time),
        "--output-interval", repr(interop.STEP),
        "--output-variables", *OUTPUTS,
        "--output-file", str(tmp_path / "out.csv"),
    ]
    if experiment.start_values:
        command += ["--start-values"] + [str(x) for kv in experiment.start_values.items() for x in kv]
    if experiment.source is not None:
        table = interop.input_road_table(fmu_file, experiment)
        with open(tmp_path / "input.csv", "w") as f:
            f.write('"time","x_g"\n')
            f.writelines(f"{float(t)!r},{float(x)!r}\n" for t, x in table)
        command += ["--input-file", str(tmp_path / "input.csv")]
    subprocess.run(command, capture_output=True, text=True, check=True)
    result = read_csv(str(tmp_path / "out.csv"))
    times, reference = fmpy_reference(name)
    np.testing.assert_array_equal(result["time"][1:], times)
    rows = np.column_stack([result[n][1:] for n in OUTPUTS])
    agreed = interop.assert_agrees(rows, reference, what=f"fmpy CLI {name}")
    interop.record(f"fmpy CLI {fmpy.__version__}", name, "fmpy simulate_fmu", agreed, "CSV round trip")
