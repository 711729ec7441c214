"""The master's tolerance sets the accuracy of both FMUs: fmpy's
`relative_tolerance` reaches `fmi2SetupExperiment` and
`fmi3EnterInitializationMode`, the DefaultExperiment declares the default,
and a tolerance out of range is refused with its value.

The FMU and the command line share the library, so a run of either FMU at a
tolerance equals `tdvass simulate --tolerance` at the same tolerance (to
rounding), and two tolerances give two different internal steps, hence
different last digits."""

import json
import subprocess
from pathlib import Path

import pytest
from fmpy import read_model_description, simulate_fmu

from fmu_helpers import REPO_ROOT, fmu_path

RMS = ["rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection", "objective"]
DURATION = 3.0


def fmus():
    fmi2 = fmu_path()
    return [fmi2, fmi2.with_name("tdvass-fmi3.fmu")]


def cli(tolerance):
    binary = REPO_ROOT / "target" / "release" / "tdvass"
    out = subprocess.run(
        [str(binary), "simulate", "--json", "--duration", str(DURATION), "--tolerance", str(tolerance)],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    return json.loads(out)


@pytest.mark.parametrize("fmu", fmus(), ids=["fmi2", "fmi3"])
def test_the_default_experiment_declares_the_tolerance(fmu):
    experiment = read_model_description(str(fmu)).defaultExperiment
    assert float(experiment.tolerance) == 1e-6


@pytest.mark.parametrize("fmu", fmus(), ids=["fmi2", "fmi3"])
def test_the_masters_tolerance_is_honoured(fmu):
    results = {}
    for tolerance in (1e-4, 1e-9):
        result = simulate_fmu(
            str(fmu), stop_time=DURATION, relative_tolerance=tolerance, output=RMS
        )
        reference = cli(tolerance)
        for name in RMS:
            ours, theirs = result[name][-1], reference[name]
            assert abs(ours - theirs) <= 1e-12 * abs(theirs), (fmu.name, tolerance, name, ours, theirs)
        results[tolerance] = {name: result[name][-1] for name in RMS}
    # Different tolerances, different steps (1e-4: 10 ms, 1e-9: about
    # 0.6 ms), so the outputs differ in their last digits, by less than the
    # looser tolerance.
    assert cli(1e-4)["internal_step"] > cli(1e-9)["internal_step"]
    for name in RMS:
        loose, tight = results[1e-4][name], results[1e-9][name]
        assert loose != tight, name
        assert abs(loose - tight) <= 1e-4 * abs(tight), name


@pytest.mark.parametrize("fmu", fmus(), ids=["fmi2", "fmi3"])
@pytest.mark.parametrize(
    "tolerance, printed", [(0.5, "0.5"), (-1e-6, "-0.000001"), (1e-15, "0.000000000000001")]
)
def test_a_tolerance_out_of_range_is_refused_with_its_value(fmu, tolerance, printed):
    messages = []

    def logger(*args):
        messages.append(" ".join(str(a) for a in args))

    with pytest.raises(Exception):
        simulate_fmu(
            str(fmu),
            stop_time=0.01,
            relative_tolerance=tolerance,
            logger=logger,
            debug_logging=True,
        )
    text = "\n".join(messages)
    assert "`tolerance`" in text and printed in text, text
