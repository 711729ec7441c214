"""The reference results both FMUs carry (FMI-LS-REF): the manifest
extra/org.fmi-standard.fmi-ls-ref/fmi-ls-manifest.xml names tdvass_out.csv
beside it, the outputs of the default experiment written by fmu-build. fmpy,
simulating each FMU (FMI 2.0 and FMI 3.0) at the CSV's output times,
reproduces every column to 1e-12 of that output's peak |value|, and on the
machine that built it exactly; and fmpy's validation stays clean with the
extra files in the archives."""

from __future__ import annotations

import csv
import io
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu
from fmu_helpers import fmu_path

LS_REF = "extra/org.fmi-standard.fmi-ls-ref"
MANIFEST = f"{LS_REF}/fmi-ls-manifest.xml"
MANIFEST_NAMESPACE = "http://fmi-standard.org/fmi-ls-manifest"
RELATIVE_TOLERANCE = 1e-12  # of each output's peak |value|

FMUS = {"FMI 2.0": "tdvass.fmu", "FMI 3.0": "tdvass-fmi3.fmu"}


@pytest.fixture(scope="module", params=list(FMUS), ids=list(FMUS))
def fmu(request) -> Path:
    path = fmu_path().with_name(FMUS[request.param])
    if not path.is_file():
        pytest.fail(f"{path} not found; build it with `cargo run --release -p fmu-build`")
    return path


def related_results(archive: zipfile.ZipFile) -> str:
    """The path in the archive of the results the manifest names."""
    root = ET.fromstring(archive.read(MANIFEST))
    assert root.tag == "fmiReferences"
    assert root.get(f"{{{MANIFEST_NAMESPACE}}}fmi-ls-name") == "org.fmi-standard.fmi-ls-ref"
    assert root.get(f"{{{MANIFEST_NAMESPACE}}}fmi-ls-version")
    related = [r for r in root.findall("Related") if r.get("role") == "result"]
    assert len(related) == 1, ET.tostring(root)
    assert related[0].get("type") == "text/csv"
    return f"{LS_REF}/{related[0].get('source')}"


def read_results(fmu: Path) -> tuple[list[str], np.ndarray]:
    with zipfile.ZipFile(fmu) as archive:
        entry = related_results(archive)
        text = archive.read(entry).decode("ascii")
    rows = list(csv.reader(io.StringIO(text)))
    header, values = rows[0], np.array([[float(x) for x in row] for row in rows[1:]])
    assert values.shape == (len(rows) - 1, len(header))
    return header, values


def scalar_real_outputs(fmu: Path) -> list[str]:
    md = read_model_description(str(fmu))
    return [v.name for v in md.modelVariables
            if v.causality == "output" and v.type in ("Real", "Float64") and not v.dimensions]


def worst_difference(reference: np.ndarray, simulated: np.ndarray) -> float:
    """The largest |simulated - reference| over the column's peak
    |reference| (inf where a zero column is not matched exactly)."""
    peak = float(np.max(np.abs(reference)))
    difference = float(np.max(np.abs(simulated - reference)))
    if peak == 0.0:
        return 0.0 if difference == 0.0 else float("inf")
    return difference / peak


def test_manifest_names_the_results_of_every_output(fmu):
    name = "tdvass_out.csv"
    with zipfile.ZipFile(fmu) as archive:
        assert related_results(archive) == f"{LS_REF}/{name}"
        assert f"{LS_REF}/{name}" in archive.namelist()
    header, values = read_results(fmu)
    assert header[0] == "time"
    assert header[1:] == scalar_real_outputs(fmu)
    experiment = read_model_description(str(fmu)).defaultExperiment
    assert values[0, 0] == float(experiment.startTime)
    assert values[-1, 0] == pytest.approx(float(experiment.stopTime), abs=1e-12)
    steps = np.diff(values[:, 0])
    assert np.allclose(steps, steps[0], rtol=1e-9, atol=0) and steps[0] >= 0.01
    # Not a table of zeros: the body moves, the RMS values grow.
    assert np.max(np.abs(values[:, header.index("x_s")])) > 1e-3
    assert values[-1, header.index("rms_body_acceleration")] == pytest.approx(0.3068, abs=1.5e-4)


def test_simulation_reproduces_every_column(fmu):
    header, reference = read_results(fmu)
    interval = float(reference[1, 0] - reference[0, 0])
    result = simulate_fmu(str(fmu), output_interval=interval, output=header[1:])
    assert len(result) == len(reference), f"{len(result)} rows against {len(reference)}"
    assert np.max(np.abs(result["time"] - reference[:, 0])) <= 1e-12
    for column, name in enumerate(header[1:], start=1):
        difference = worst_difference(reference[:, column], result[name])
        assert difference <= RELATIVE_TOLERANCE, f"{fmu.name}: {name} differs by {difference:.3g} of its peak"


def test_the_comparison_sees_a_difference_of_1e_11_of_the_peak():
    reference = np.array([0.0, 2.0, -4.0, 1.0])
    assert worst_difference(reference, reference.copy()) == 0.0
    changed = reference.copy()
    changed[3] += 4e-11
    assert worst_difference(reference, changed) == pytest.approx(1e-11)
    assert worst_difference(reference, changed) > RELATIVE_TOLERANCE
    assert worst_difference(np.zeros(3), np.array([0.0, 1e-300, 0.0])) == float("inf")


def test_the_shipped_library_computes_the_slaves_bits(fmu):
    """The FMU's library (built with a profile, fmu-build/src/pgo.rs) and
    the slave fmu-build ran for the reference results (built without one)
    perform the same floating-point operations: on this machine every
    output at every output time is the same double."""
    header, reference = read_results(fmu)
    interval = float(reference[1, 0] - reference[0, 0])
    result = simulate_fmu(str(fmu), output_interval=interval, output=header[1:])
    assert np.array_equal(result["time"], reference[:, 0])
    for column, name in enumerate(header[1:], start=1):
        differing = int(np.count_nonzero(result[name] != reference[:, column]))
        assert differing == 0, f"{fmu.name}: {name} differs at {differing} output times"


def test_fmpy_validation_is_clean(fmu):
    assert validate_fmu(str(fmu)) == []
    fmpy_script = Path(sys.executable).parent / "fmpy"
    done = subprocess.run([str(fmpy_script), "validate", str(fmu)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == "No problems found.", done.stdout + done.stderr

