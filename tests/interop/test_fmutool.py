"""fmu-manipulation-toolbox's checker: `fmutool -input tdvass.fmu -check`
runs its XSD conformity check and its semantic checks of the description."""

import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

import interop


def test_fmutool_check_finds_nothing(fmu_file):
    fmutool = Path(sys.executable).parent / "fmutool"
    done = subprocess.run([str(fmutool), "-input", str(fmu_file), "-check"],
                          capture_output=True, text=True, timeout=120)
    log = done.stdout + done.stderr
    assert done.returncode == 0, log
    assert "This FMU seems to be compliant with FMI-2.0." in log, log
    assert "No semantic error against the FMI-2 standard." in log, log
    findings = [line for line in log.splitlines() if line.startswith(("ERROR", "WARNING", "CRITICAL"))]
    assert not findings, log
    interop.record(f"fmutool {version('fmu-manipulation-toolbox')}", "-", "-check", "no findings")
