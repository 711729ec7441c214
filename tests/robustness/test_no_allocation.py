"""No heap allocation while stepping (docs/fmu.md, "Real-time"): the C
harness realtime.c, with its own malloc family interposed, drives the
shipped Linux library of each FMU over every road x tire mode x step
pattern (aligned 1 ms, 0.7 ms, a varying master, 10 ms steps of many
internal steps) for 30 s, setting g and the road input and reading every
output, lift_off_count and the output derivatives at every point (FMI 3.0:
intermediate updates with early returns too), restores a serialized copy
of its state in the middle of the run (the state functions themselves are
not counted), and counts every allocation from the return of Exit
Initialization Mode on. The calls that change g's
value are counted apart (they rebuild the operators and check stability).

Model Exchange (`count-me`): the same libraries instantiated for Model
Exchange and driven as a fixed-step real-time master drives them (Heun's
method at the case's steps, a trial point at each step's end, events,
CompletedIntegratorStep, every output read), also after restoring a
serialized state in the middle of the run, allocate nothing either."""

import re
import shutil
import subprocess
from pathlib import Path

import pytest

import fmi2
import fmi3

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "realtime.c"
COUNT = re.compile(r"allocations (\d+) calls (\d+) \(g value changes: 2 calls, (\d+) allocations\)")
COUNT_MODEL_EXCHANGE = re.compile(r"allocations (\d+) steps (\d+) \(restoring a serialized state: (\d+) allocations\)")


@pytest.fixture(scope="module")
def harness(tmp_path_factory):
    if not shutil.which("gcc"):
        pytest.fail("gcc is needed to build tests/robustness/realtime.c")
    out = tmp_path_factory.mktemp("realtime") / "realtime"
    subprocess.run(["gcc", "-O2", "-Wall", "-Wextra", "-Werror", "-rdynamic", "-o", str(out), str(SOURCE),
                    "-ldl", "-lm"], check=True)
    return out


def cases() -> list[str]:
    """The case names, as the harness defines them (parsed from its
    source, so that collection needs no compiler)."""
    text = SOURCE.read_text()
    assert "add_case(ROAD_ISO, 4, 20.0" in text and "add_case(ROAD_ISO, 5, 30.0" in text
    names = []
    for pattern in ["aligned", "0.7ms", "varying", "10ms"]:
        for tire in ["bilateral", "unilateral"]:
            names += [f"input-{tire}-{pattern}", f"harmonic-{tire}-{pattern}", f"iso-D-20-{tire}-{pattern}",
                      f"iso-E-30-{tire}-{pattern}", f"paper-{tire}-{pattern}"]
    return names


FMUS = {
    2: (fmi2.library_path, fmi2.guid, fmi2.variables),
    3: (fmi3.library_path, fmi3.instantiation_token, fmi3.variables),
}
LIBRARIES = {}


def library(version: int) -> tuple[str, str]:
    if version not in LIBRARIES:
        path, token, _ = FMUS[version]
        LIBRARIES[version] = (str(path()), token())
    return LIBRARIES[version]


def test_the_case_names_are_the_harness_list(harness):
    listed = subprocess.run([str(harness), "list"], capture_output=True, text=True, check=True).stdout.split()
    assert listed == cases()


@pytest.mark.parametrize("version", [2, 3])
def test_the_harness_value_references_are_the_model_descriptions(version):
    text = SOURCE.read_text()
    variables = FMUS[version][2]()
    for name, vr in re.findall(r"VR_([A-Z_]+) = (\d+)", text):
        assert variables[name.lower()][0] == int(vr), name
    outputs = {int(v) for v in re.search(r"OUTPUTS\[\] = \{([^}]*)\}", text).group(1).split(",")}
    real_outputs = {vr for vr, kind, causality, _ in variables.values()
                    if causality == "output" and kind in ("Real", "Float64")}
    assert outputs == real_outputs


def count(harness, mode, version, case, pattern):
    """Runs the harness's `mode` (count, count-me) on `case`: the numbers
    its line `pattern` reports, and its exit code."""
    lib, token = library(version)
    run = subprocess.run([str(harness), mode, str(version), lib, token, case], capture_output=True,
                         text=True, timeout=300)
    found = pattern.search(run.stdout)
    assert found, f"exit {run.returncode}: {run.stdout}{run.stderr}"
    return *map(int, found.groups()), run.returncode


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("case", cases())
def test_stepping_allocates_nothing(harness, version, case):
    allocations, calls, gain_changes, returncode = count(harness, "count", version, case, COUNT)
    assert calls >= 3000
    # The counter sees the library's allocations: the two changes of g
    # allocate (the stability check of the new gain).
    assert gain_changes > 0
    assert allocations == 0, f"{allocations} allocations in {calls} calls of {case} (FMI {version})"
    assert returncode == 0


def test_the_harness_state_counts_are_the_model_descriptions():
    text = SOURCE.read_text()
    description = (HERE.parent.parent / "modelDescription" / "modelDescription.xml").read_text()
    states = int(re.search(r"#define N_STATES (\d+)", text).group(1))
    indicators = int(re.search(r"#define N_INDICATORS (\d+)", text).group(1))
    assert states == description.count('name="der(')
    assert indicators == int(re.search(r'numberOfEventIndicators="(\d+)"', description).group(1))


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("case", cases())
def test_model_exchange_allocates_nothing(harness, version, case):
    allocations, steps, restore, returncode = count(harness, "count-me", version, case, COUNT_MODEL_EXCHANGE)
    assert steps >= 15000
    # The counter sees the library's allocations: restoring the
    # serialized state allocates (the copies of the model).
    assert restore > 0
    assert allocations == 0, f"{allocations} allocations in {steps} steps of {case} (FMI {version})"
    assert returncode == 0
