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
serialized state in the middle of the run, allocate nothing either.

The corner and the chassis (driven in Co-Simulation), each from its own FMU,
for 10 s with a serialized state restored after 5 s, both with
`input_extrapolation = 1` as the full car's system files set it (the
attachment moved on the extrapolated velocity, the forces ramped along
their last two values, on top of what holding them does). The corner: every
road x tire mode x the aligned, varying and 10 ms patterns, under a point
mass moved by the body_force it reads (body_displacement, body_velocity
and x_g set before every step; FMI 2.0: the body inputs' derivatives too,
which the corner ignores with a warning; FMI 3.0: intermediate updates
and early returns), every output, lift_off_count and the output
derivatives read, g changed and changed back (counted apart). The
chassis: four changing forces set before every step (FMI 2.0: force_fl's
order-1 derivative too), every output read, over 1 ms steps, libcosim's
clock (1 ms and 1 ms + 1e-12 in turn), the varying master (8 lengths: a
new step length, hence new W_k maps, at every step) and 10 ms steps."""

import os
import re
import shutil
import subprocess
import tempfile
import zipfile
from pathlib import Path

import pytest

import fmi2
import fmi3

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "realtime.c"
COUNT = re.compile(r"allocations (\d+) calls (\d+) \(g value changes: 2 calls, (\d+) allocations\)")
COUNT_MODEL_EXCHANGE = re.compile(r"allocations (\d+) steps (\d+) \(restoring a serialized state: (\d+) allocations\)")
COUNT_CHASSIS = re.compile(r"allocations (\d+) calls (\d+) \(restoring a serialized state: (\d+) allocations\)")


@pytest.fixture(scope="module")
def harness(tmp_path_factory):
    if not shutil.which("gcc"):
        pytest.fail("gcc is needed to build tests/robustness/realtime.c")
    out = tmp_path_factory.mktemp("realtime") / "realtime"
    subprocess.run(["gcc", "-O2", "-Wall", "-Wextra", "-Werror", "-rdynamic", "-o", str(out), str(SOURCE),
                    "-ldl", "-lm"], check=True)
    return out


def cases() -> list[str]:
    """The quarter car's case names, as the harness defines them (parsed
    from its source, so that collection needs no compiler)."""
    text = SOURCE.read_text()
    assert "add_case(ROAD_ISO, 4, 20.0" in text and "add_case(ROAD_ISO, 5, 30.0" in text
    names = []
    for pattern in ["aligned", "0.7ms", "varying", "10ms"]:
        for tire in ["bilateral", "unilateral"]:
            names += [f"input-{tire}-{pattern}", f"harmonic-{tire}-{pattern}", f"iso-D-20-{tire}-{pattern}",
                      f"iso-E-30-{tire}-{pattern}", f"paper-{tire}-{pattern}"]
    return names


def corner_cases() -> list[str]:
    """The corner's case names (as the harness defines them)."""
    text = SOURCE.read_text()
    assert "corner_patterns[] = {PATTERN_ALIGNED, PATTERN_VARYING, PATTERN_LONG}" in text
    names = []
    for pattern in ["aligned", "varying", "10ms"]:
        for tire in ["bilateral", "unilateral"]:
            names += [f"corner-input-{tire}-{pattern}", f"corner-harmonic-{tire}-{pattern}",
                      f"corner-iso-D-20-{tire}-{pattern}", f"corner-iso-E-30-{tire}-{pattern}",
                      f"corner-paper-{tire}-{pattern}"]
    return names


def chassis_cases() -> list[str]:
    """The chassis's case names (as the harness defines them)."""
    text = SOURCE.read_text()
    assert "chassis_patterns[] = {PATTERN_ALIGNED, PATTERN_LIBCOSIM, PATTERN_VARYING, PATTERN_LONG}" in text
    return ["chassis-aligned", "chassis-libcosim", "chassis-varying", "chassis-10ms"]


# The FMU of each model and version: (module, its file).
FMU_FILES = {
    ("quarter car", 2): (fmi2, fmi2.fmu_file),
    ("quarter car", 3): (fmi3, fmi3.fmu_file),
    ("corner", 2): (fmi2, fmi2.corner_fmu_file),
    ("corner", 3): (fmi3, fmi3.corner_fmu_file),
    ("chassis", 2): (fmi2, fmi2.chassis_fmu_file),
    ("chassis", 3): (fmi3, fmi3.chassis_fmu_file),
}
BINARY = {2: "binaries/linux64/tdvass.so", 3: "binaries/x86_64-linux/tdvass.so"}
LIBRARIES = {}


def model_of(case: str) -> str:
    return "corner" if case.startswith("corner-") else "chassis" if case.startswith("chassis-") else "quarter car"


def variables_of(model: str, version: int) -> dict:
    module, fmu = FMU_FILES[(model, version)]
    return module.variables(fmu())


def library(model: str, version: int) -> tuple[str, str]:
    """The shared library of the model's own FMU (or $TDVASS_SO) and its
    GUID / instantiation token."""
    if (model, version) not in LIBRARIES:
        module, fmu = FMU_FILES[(model, version)]
        token = module.guid(fmu()) if version == 2 else module.instantiation_token(fmu())
        if model == "quarter car":
            path = module.library_path()
        elif os.environ.get("TDVASS_SO"):
            path = Path(os.environ["TDVASS_SO"])
        else:
            path = Path(tempfile.mkdtemp(prefix="tdvass-realtime-")) / "tdvass.so"
            with zipfile.ZipFile(fmu()) as z:
                path.write_bytes(z.read(BINARY[version]))
        LIBRARIES[(model, version)] = (str(path), token)
    return LIBRARIES[(model, version)]


def test_the_case_names_are_the_harness_list(harness):
    listed = subprocess.run([str(harness), "list"], capture_output=True, text=True, check=True).stdout.split()
    assert listed == cases() + corner_cases() + chassis_cases()


# The quarter car's VR_* the corner run uses too.
CORNER_SHARED = {"g", "road", "road_class", "vehicle_speed", "x_g", "tire_contact", "lift_off_count"}


@pytest.mark.parametrize("version", [2, 3])
def test_the_harness_value_references_are_the_model_descriptions(version):
    text = SOURCE.read_text()
    prefixes = {"": "quarter car", "CORNER": "corner", "CHASSIS": "chassis"}
    variables = {model: variables_of(model, version) for model in prefixes.values()}
    found = re.findall(r"\b(?:(CORNER|CHASSIS)_)?VR_([A-Z_]+) = (\d+)", text)
    assert {prefix for prefix, _, _ in found} == set(prefixes)
    for prefix, name, vr in found:
        assert variables[prefixes[prefix]][name.lower()][0] == int(vr), (prefix, name)
        if not prefix and name.lower() in CORNER_SHARED:
            assert variables["corner"][name.lower()][0] == int(vr), name
    assert CORNER_SHARED <= {name.lower() for prefix, name, _ in found if not prefix}
    for prefix, model in prefixes.items():
        array = re.search(rf"\b{prefix + '_' if prefix else ''}OUTPUTS\[\] = \{{([^}}]*)\}}", text)
        outputs = [int(v) for v in array.group(1).split(",")]
        real_outputs = {vr for vr, kind, causality, _ in variables[model].values()
                        if causality == "output" and kind in ("Real", "Float64")}
        assert len(outputs) == len(set(outputs)) and set(outputs) == real_outputs, model
    # The corner's point mass reads body_force as the last of its outputs.
    corner_outputs = re.search(r"\bCORNER_OUTPUTS\[\] = \{([^}]*)\}", text).group(1).split(",")
    assert int(corner_outputs[-1]) == variables["corner"]["body_force"][0]


def count(harness, mode, version, case, pattern):
    """Runs the harness's `mode` (count, count-me) on `case`: the numbers
    its line `pattern` reports, and its exit code."""
    lib, token = library(model_of(case), version)
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


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("case", corner_cases())
def test_the_corner_allocates_nothing(harness, version, case):
    allocations, calls, gain_changes, returncode = count(harness, "count", version, case, COUNT)
    assert calls >= 1000
    # The counter sees the library's allocations: the two changes of g.
    assert gain_changes > 0
    assert allocations == 0, f"{allocations} allocations in {calls} calls of {case} (FMI {version})"
    assert returncode == 0


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("case", chassis_cases())
def test_the_chassis_allocates_nothing(harness, version, case):
    allocations, calls, restore, returncode = count(harness, "count", version, case, COUNT_CHASSIS)
    assert calls >= 1000
    # The counter sees the library's allocations: restoring the
    # serialized state allocates.
    assert restore > 0
    assert allocations == 0, f"{allocations} allocations in {calls} calls of {case} (FMI {version})"
    assert returncode == 0
