"""The master's tolerance sets the accuracy of both FMUs: fmpy's
`relative_tolerance` reaches `fmi2SetupExperiment` and
`fmi3EnterInitializationMode`, the DefaultExperiment declares the default,
and a tolerance out of range is refused with its value.

Each FMU logs its tolerance and internal step at the end of
initialization; a run at a tolerance is within it of a run at 1e-10."""

import re

import pytest
from fmpy import read_model_description, simulate_fmu

from fmu_helpers import fmu_path

RMS = ["rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection", "objective"]
DURATION = 3.0


def fmus():
    fmi2 = fmu_path()
    return [fmi2, fmi2.with_name("tdvass-fmi3.fmu")]


@pytest.mark.parametrize("fmu", fmus(), ids=["fmi2", "fmi3"])
def test_the_default_experiment_declares_the_tolerance(fmu):
    experiment = read_model_description(str(fmu)).defaultExperiment
    assert float(experiment.tolerance) == 1e-6


def run(fmu, tolerance):
    """The RMS outputs at the end and the internal step the FMU logged."""
    messages = []

    def logger(*args):
        messages.append(" ".join(a.decode() if isinstance(a, bytes) else str(a) for a in args))

    result = simulate_fmu(
        str(fmu),
        stop_time=DURATION,
        relative_tolerance=tolerance,
        output=RMS,
        logger=logger,
        debug_logging=True,
    )
    text = "\n".join(messages)
    match = re.search(r"tolerance ([0-9.e-]+), internal step ([0-9.e-]+) s", text)
    assert match, text
    return {name: result[name][-1] for name in RMS}, float(match.group(1)), float(match.group(2))


@pytest.mark.parametrize("fmu", fmus(), ids=["fmi2", "fmi3"])
def test_the_masters_tolerance_is_honoured(fmu):
    reference, _, fine_step = run(fmu, 1e-10)
    steps = []
    for tolerance in (1e-4, 1e-7):
        outputs, logged, step = run(fmu, tolerance)
        assert logged == tolerance
        steps.append(step)
        for name in RMS:
            error = abs(outputs[name] - reference[name]) / abs(reference[name])
            assert error <= tolerance, (fmu.name, tolerance, name, error)
    # Tighter, shorter (1e-4: 1 ms, the DefaultExperiment stepSize it
    # divides; 1e-10: a fraction of it).
    assert steps[0] >= steps[1] > fine_step
    # Without a tolerance from the master (fmpy then passes the
    # DefaultExperiment's), the default.
    _, logged, step = run(fmu, None)
    assert logged == 1e-6
    # The internal step divides the DefaultExperiment stepSize (1 ms): a
    # master stepping by it meets internal nodes only.
    assert abs(1e-3 / step - round(1e-3 / step)) < 1e-9, step


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
