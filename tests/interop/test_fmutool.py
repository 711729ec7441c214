"""fmu-manipulation-toolbox's checker: `fmutool -input tdvass.fmu -check`
runs its XSD conformity check and its semantic checks of the description
(of the quarter car's FMI 2.0 FMU and of both corner and both chassis
FMUs)."""

import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

import interop


def check_finds_nothing(fmu, fmi_version):
    fmutool = Path(sys.executable).parent / "fmutool"
    done = subprocess.run([str(fmutool), "-input", str(fmu), "-check"],
                          capture_output=True, text=True, timeout=120)
    log = done.stdout + done.stderr
    assert done.returncode == 0, log
    assert f"This FMU seems to be compliant with FMI-{fmi_version}." in log, log
    assert f"No semantic error against the FMI-{fmi_version[0]} standard." in log, log
    findings = [line for line in log.splitlines() if line.startswith(("ERROR", "WARNING", "CRITICAL"))]
    assert not findings, log


def test_fmutool_check_finds_nothing(fmu_file):
    check_finds_nothing(fmu_file, "2.0")
    interop.record(f"fmutool {version('fmu-manipulation-toolbox')}", "-", "-check", "no findings")


def test_fmutool_check_finds_nothing_in_the_corner(corner_file):
    fmi_version = interop.CORNER_FMUS[corner_file.name]
    check_finds_nothing(corner_file, fmi_version)
    interop.record(f"fmutool {version('fmu-manipulation-toolbox')}", f"corner {fmi_version}", "-check", "no findings")


def test_fmutool_check_finds_nothing_in_the_chassis(chassis_file):
    fmi_version = interop.CHASSIS_FMUS[chassis_file.name]
    check_finds_nothing(chassis_file, fmi_version)
    interop.record(f"fmutool {version('fmu-manipulation-toolbox')}", f"chassis {fmi_version}", "-check", "no findings")
