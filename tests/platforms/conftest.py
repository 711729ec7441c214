"""Fixtures of the cross-platform tests: the FMU's binaries for each platform,
the C harness (harness.c) compiled for each platform, and its results.

Platforms and how the harness runs there:
  linux64  binaries/linux64/tdvass.so of the FMU, natively
  win64    binaries/win64/tdvass.dll of the FMU, under wine
           (/usr/lib/wine/wine64, a private WINEPREFIX in target/platforms)
  aarch64  target/aarch64-unknown-linux-gnu/release/libtdvass_fmi2.so (FMI 2.0
           has no aarch64 platform folder, so it is not in the FMU), under
           qemu-user (`qemu-aarch64 -L /usr/aarch64-linux-gnu`)

The FMI 3.0 FMU (tdvass-fmi3.fmu) carries all three, under the platform
tuples x86_64-linux, x86_64-windows and aarch64-linux; harness_fmi3.c runs them
under the same runners (the `platforms3` and `results3` fixtures, results
in target/platforms/fmi3/).

The corner's and the chassis's FMUs carry the same libraries (their GUID or
instantiationToken picks the model): in the same run, each harness drives
them for half a second with inputs set before every 1 ms step from the
tables that DRIVEN_RUNS defines (the `driven` fixture; drive_<run>.csv
beside the other results), in Co-Simulation and, in the runs named *_me, in
Model Exchange: the harness integrates each step with ten explicit Euler
steps of 0.1 ms under the inputs held, handles the events and writes the
continuous states, their derivatives and the event indicators beside the
outputs; their numbers come from the FMU's modelDescription.xml (`Model`).

Build everything first with `cargo run --release -p fmu-build -- --all-platforms`.
"""

import math
import os
import re
import shutil
import struct
import subprocess
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
WINE = Path("/usr/lib/wine/wine64")
AARCH64_SYSROOT = Path("/usr/aarch64-linux-gnu")
# The harness's limit of a run (the slowest, under qemu, takes seconds).
RUN_TIMEOUT_S = 600

# Value references the harness sets by number (harness.c), by name.
HARNESS_VARIABLES = {
    "variant": 1, "g": 10, "tau": 11, "road": 12, "road_class": 15, "road_seed": 18, "x_s": 31,
}

# The same for harness_fmi3.c (FMI 3.0): name -> (value reference, element).
HARNESS3_VARIABLES = {
    "variant": (1, "Enumeration"), "road": (12, "Enumeration"), "road_class": (15, "Enumeration"),
    "road_seed": (18, "Int32"),
}

# Largest relative difference to the linux64 run that the tests accept:
# none. Every transcendental function the results depend on comes from one
# pure-Rust implementation (tdvass::math), so every platform computes the
# same bits.
RELATIVE_TOLERANCE = 0.0

# platform -> {"file": [max relative difference, values compared]} for the
# summary at the end of the run.
OBSERVED: dict[str, dict[str, list[float]]] = {}

# One line per Linux library checked by test_elf_policy.py (highest GLIBC
# version, NEEDED), for the summary at the end of the run.
ELF_POLICY: list[str] = []


def target_dir() -> Path:
    override = os.environ.get("CARGO_TARGET_DIR")
    if not override:
        return ROOT / "target"
    path = Path(override)
    return path if path.is_absolute() else ROOT / path


WORK = target_dir() / "platforms"
FMU = target_dir() / "fmu" / "tdvass.fmu"
FMU3 = target_dir() / "fmu" / "tdvass-fmi3.fmu"
# The corner's FMUs (Co-Simulation and Model Exchange) carry the same libraries.
CORNER = target_dir() / "fmu" / "tdvass-corner.fmu"
CORNER3 = target_dir() / "fmu" / "tdvass-corner-fmi3.fmu"
# The chassis's FMUs, the same again.
CHASSIS = target_dir() / "fmu" / "tdvass-chassis.fmu"
CHASSIS3 = target_dir() / "fmu" / "tdvass-chassis-fmi3.fmu"
INCLUDE = HERE.parent / "include"  # fmi3_types.h
BUILD_HINT = "build it with `cargo run --release -p fmu-build -- --all-platforms`"


def require_tool(path: str, package: str) -> str:
    found = shutil.which(path) if "/" not in path else (path if Path(path).exists() else None)
    if not found:
        pytest.fail(f"{path} not found: install the Debian package {package}")
    return found


def run(command: list[str], **kwargs) -> subprocess.CompletedProcess:
    result = subprocess.run(command, capture_output=True, text=True, timeout=RUN_TIMEOUT_S, **kwargs)
    if result.returncode != 0:
        pytest.fail(f"{' '.join(map(str, command))} exited with {result.returncode}:\n"
                    f"{result.stdout}\n{result.stderr}")
    return result


@dataclass
class Description:
    guid: str
    outputs: list[int]  # value references of the Real outputs
    variables: dict[str, int]  # name -> value reference


@pytest.fixture(scope="session")
def fmu() -> zipfile.ZipFile:
    if not FMU.is_file():
        pytest.fail(f"{FMU} not found; {BUILD_HINT}")
    return zipfile.ZipFile(FMU)


@pytest.fixture(scope="session")
def description(fmu) -> Description:
    root = ET.fromstring(fmu.read("modelDescription.xml"))
    variables, outputs = {}, []
    for variable in root.iter("ScalarVariable"):
        vr = int(variable.get("valueReference"))
        variables[variable.get("name")] = vr
        if variable.get("causality") == "output" and variable.find("Real") is not None:
            outputs.append(vr)
    for name, vr in HARNESS_VARIABLES.items():
        assert variables.get(name) == vr, f"harness.c sets `{name}` as value reference {vr}"
    assert outputs, "the description declares no Real output"
    return Description(root.get("guid"), outputs, variables)


@dataclass
class Platform:
    name: str
    compiler: list[str]  # compiles harness.c: compiler and flags
    compiler_package: str
    library: Path
    runner: list[str]  # prefix of the command that runs the harness
    executable: str  # the harness's file name
    source: str = "harness.c"
    work: Path = WORK

    @property
    def dir(self) -> Path:
        return self.work / self.name

    def host_path(self, path: Path) -> str:
        """`path` as the harness sees it (wine maps / to drive Z:)."""
        if self.name == "win64":
            return "Z:" + str(path).replace("/", "\\")
        return str(path)


def extracted(fmu: zipfile.ZipFile, entry: str, name: str) -> Path:
    if entry not in fmu.namelist():
        pytest.fail(f"{fmu.filename} has no {entry}; {BUILD_HINT}")
    path = WORK / "binaries" / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(fmu.read(entry))
    return path


def wine_environment() -> dict[str, str]:
    """Quiet, self-contained wine: a private prefix under target/."""
    return dict(
        os.environ,
        WINEPREFIX=str(WORK / "wineprefix"),
        WINEDEBUG="-all",
        WINEDLLOVERRIDES="mscoree,mshtml=",  # no Mono/Gecko installers
    )


@pytest.fixture(scope="session")
def platforms(fmu) -> dict[str, Platform]:
    aarch64_library = target_dir() / "aarch64-unknown-linux-gnu" / "release" / "libtdvass_fmi2.so"
    if not aarch64_library.is_file():
        pytest.fail(f"{aarch64_library} not found; {BUILD_HINT}")
    return {
        "linux64": Platform("linux64", ["gcc", "-ldl"], "gcc",
                            extracted(fmu, "binaries/linux64/tdvass.so", "linux64/tdvass.so"),
                            [], "harness"),
        "win64": Platform("win64", ["x86_64-w64-mingw32-gcc", "-static"], "gcc-mingw-w64-x86-64",
                          extracted(fmu, "binaries/win64/tdvass.dll", "win64/tdvass.dll"),
                          [require_tool(str(WINE), "wine64")], "harness.exe"),
        "aarch64": Platform("aarch64", ["aarch64-linux-gnu-gcc", "-ldl"], "gcc-aarch64-linux-gnu",
                            aarch64_library,
                            [require_tool("qemu-aarch64", "qemu-user"), "-L", str(AARCH64_SYSROOT)],
                            "harness"),
    }


def build_harness(platform: Platform) -> Path:
    platform.dir.mkdir(parents=True, exist_ok=True)
    compiler = require_tool(platform.compiler[0], platform.compiler_package)
    executable = platform.dir / platform.executable
    run([compiler, "-O2", "-std=c11", "-Wall", "-Wextra", "-Werror", f"-I{INCLUDE}", "-o", str(executable),
         str(HERE / platform.source), *platform.compiler[1:]])
    if platform.name == "win64":
        # The stand-in for bcryptprimitives.dll, which Debian's wine lacks
        # (see bcryptprimitives_shim.c): beside the harness, never in the FMU.
        run([compiler, "-O2", "-shared", "-o", str(platform.dir / "bcryptprimitives.dll"),
             str(HERE / "bcryptprimitives_shim.c"), "-ladvapi32"])
    return executable


class Results:
    """The files one harness run wrote."""

    def __init__(self, platform: str, directory: Path):
        self.platform = platform
        self.dir = directory

    def table(self, name: str) -> tuple[list[str], list[list[float]]]:
        lines = (self.dir / name).read_text().splitlines()
        return lines[0].split(","), [[float(x) for x in line.split(",")] for line in lines[1:]]

    def state(self) -> bytes:
        return (self.dir / "state.bin").read_bytes()

    def bad_input(self) -> dict[str, tuple[str, str]]:
        import csv

        with open(self.dir / "bad_input.csv", newline="") as f:
            return {row["case"]: (row["result"], row["message"]) for row in csv.DictReader(f)}


_results: dict[str, Results] = {}


@pytest.fixture(scope="session")
def results(platforms, description):
    """results(platform) -> Results; the linux64 run comes first (the others
    restore its state), each platform runs once per session."""

    def get(name: str) -> Results:
        if name in _results:
            return _results[name]
        platform = platforms[name]
        linux64_state = get("linux64").dir / "state.bin" if name != "linux64" else None
        executable = build_harness(platform)
        out = platform.dir / "out"
        shutil.rmtree(out, ignore_errors=True)
        out.mkdir(parents=True)
        state_in = linux64_state or out / "state.bin"  # linux64 restores its own
        drive, drive_lines = driven_arguments(2, platform)
        command = [*platform.runner, str(executable), platform.host_path(platform.library),
                   description.guid, ",".join(map(str, description.outputs)),
                   platform.host_path(out), platform.host_path(state_in), *drive]
        env = wine_environment() if name == "win64" else None
        result = run(command, env=env, cwd=platform.dir)
        assert re.search(r"^harness: \d+ outputs x 15000 steps", result.stdout, re.M), result.stdout
        check_driven_runs(result.stdout, "harness", drive_lines)
        _results[name] = Results(name, out)
        return _results[name]

    return get


# ------------------------------------------------------------------ FMI 3.0


@pytest.fixture(scope="session")
def fmu3() -> zipfile.ZipFile:
    if not FMU3.is_file():
        pytest.fail(f"{FMU3} not found; {BUILD_HINT}")
    return zipfile.ZipFile(FMU3)


@pytest.fixture(scope="session")
def description3(fmu3) -> Description:
    """The instantiationToken (as `guid`) and Float64 outputs of the FMI 3.0 FMU."""
    root = ET.fromstring(fmu3.read("modelDescription.xml"))
    variables, outputs = {}, []
    for variable in root.find("ModelVariables"):
        vr = int(variable.get("valueReference"))
        variables[variable.get("name")] = (vr, variable.tag)
        if variable.get("causality") == "output" and variable.tag == "Float64" and variable.find("Dimension") is None:
            outputs.append(vr)
    for name, expected in HARNESS3_VARIABLES.items():
        assert variables.get(name) == expected, f"harness_fmi3.c sets `{name}` as {expected}"
    assert outputs, "the description declares no Float64 output"
    return Description(root.get("instantiationToken"), outputs, {n: vr for n, (vr, _) in variables.items()})


@pytest.fixture(scope="session")
def platforms3(fmu3) -> dict[str, Platform]:
    """The FMI 3.0 binaries under the FMI 2.0 platforms' names and runners."""
    work = WORK / "fmi3"
    return {
        "linux64": Platform("linux64", ["gcc", "-ldl"], "gcc",
                            extracted(fmu3, "binaries/x86_64-linux/tdvass.so", "fmi3/x86_64-linux/tdvass.so"),
                            [], "harness_fmi3", "harness_fmi3.c", work),
        "win64": Platform("win64", ["x86_64-w64-mingw32-gcc", "-static"], "gcc-mingw-w64-x86-64",
                          extracted(fmu3, "binaries/x86_64-windows/tdvass.dll", "fmi3/x86_64-windows/tdvass.dll"),
                          [require_tool(str(WINE), "wine64")], "harness_fmi3.exe", "harness_fmi3.c", work),
        "aarch64": Platform("aarch64", ["aarch64-linux-gnu-gcc", "-ldl"], "gcc-aarch64-linux-gnu",
                            extracted(fmu3, "binaries/aarch64-linux/tdvass.so", "fmi3/aarch64-linux/tdvass.so"),
                            [require_tool("qemu-aarch64", "qemu-user"), "-L", str(AARCH64_SYSROOT)],
                            "harness_fmi3", "harness_fmi3.c", work),
    }


_results3: dict[str, Results] = {}


@pytest.fixture(scope="session")
def results3(platforms3, description3):
    """As `results`, for harness_fmi3.c and the FMI 3.0 binaries."""

    def get(name: str) -> Results:
        if name in _results3:
            return _results3[name]
        platform = platforms3[name]
        linux64_state = get("linux64").dir / "state.bin" if name != "linux64" else None
        executable = build_harness(platform)
        out = platform.dir / "out"
        shutil.rmtree(out, ignore_errors=True)
        out.mkdir(parents=True)
        state_in = linux64_state or out / "state.bin"
        drive, drive_lines = driven_arguments(3, platform)
        command = [*platform.runner, str(executable), platform.host_path(platform.library),
                   description3.guid, ",".join(map(str, description3.outputs)),
                   platform.host_path(out), platform.host_path(state_in), *drive]
        env = wine_environment() if name == "win64" else None
        result = run(command, env=env, cwd=platform.dir)
        assert re.search(r"^harness_fmi3: \d+ outputs x 15000 steps", result.stdout, re.M), result.stdout
        check_driven_runs(result.stdout, "harness_fmi3", drive_lines)
        _results3[name] = Results(name, out)
        return _results3[name]

    return get


# ------------------------------------------------ corner and chassis, driven

DRIVEN_STEP = 1e-3  # s, the communication step of the driven runs (STEP of the harnesses)
DRIVEN_STEPS = 500  # 0.5 s
OMEGA = 2 * math.pi * 1.5  # rad/s


def body_motion(t: float) -> dict[str, float]:
    """The corner's body inputs: 1 mm sin(2π 1.5 Hz t) and its derivative."""
    return {"body_displacement": 1e-3 * math.sin(OMEGA * t), "body_velocity": 1e-3 * OMEGA * math.cos(OMEGA * t)}


def corner_forces(t: float) -> dict[str, float]:
    """The chassis's inputs (N, from the static equilibrium): each corner
    pushes differently, so that the body heaves, pitches and rolls."""
    return {"force_fl": 400 * math.sin(OMEGA * t), "force_fr": 250 * math.sin(2 * OMEGA * t),
            "force_rl": -300 * math.sin(OMEGA * t), "force_rr": 150 * (1 - math.cos(OMEGA * t))}


def force_fl_slope(t: float) -> dict[str, float]:
    """The order-1 derivative of force_fl (FMI 2.0's input derivatives)."""
    return {"force_fl": 400 * OMEGA * math.cos(OMEGA * t)}


CO_SIMULATION, MODEL_EXCHANGE = "cs", "me"  # the modes of a driven run


@dataclass
class DrivenRun:
    fmu: Path
    inputs: object  # t -> {input name: value}, set before the step from t
    derivatives: object = None  # t -> {input name: order-1 derivative}; FMI 2.0 Co-Simulation only
    mode: str = CO_SIMULATION  # or MODEL_EXCHANGE: the harness's Euler steps, the inputs held over a step
    extrapolate: bool = False  # Co-Simulation with input_extrapolation = 1, as the full car's system files set it


# (FMI version, run) -> what `harness drive` runs: the corner on its default
# harmonic road under a moving body, the chassis under four forces with the
# slope of one of them and, to compare with FMI 3.0 (which has no input
# derivatives), without it; the corner and the chassis again in Model
# Exchange (*_me), with the inputs of their Co-Simulation twins, and in
# Co-Simulation extrapolating their inputs (*_extrapolated).
DRIVEN_RUNS = {
    (2, "corner"): DrivenRun(CORNER, body_motion),
    (2, "chassis"): DrivenRun(CHASSIS, corner_forces, force_fl_slope),
    (2, "chassis_held"): DrivenRun(CHASSIS, corner_forces),
    (2, "corner_me"): DrivenRun(CORNER, body_motion, mode=MODEL_EXCHANGE),
    (2, "chassis_me"): DrivenRun(CHASSIS, corner_forces, mode=MODEL_EXCHANGE),
    (2, "corner_extrapolated"): DrivenRun(CORNER, body_motion, extrapolate=True),
    (2, "chassis_extrapolated"): DrivenRun(CHASSIS, corner_forces, extrapolate=True),
    (3, "corner"): DrivenRun(CORNER3, body_motion),
    (3, "chassis"): DrivenRun(CHASSIS3, corner_forces),
    (3, "corner_me"): DrivenRun(CORNER3, body_motion, mode=MODEL_EXCHANGE),
    (3, "chassis_me"): DrivenRun(CHASSIS3, corner_forces, mode=MODEL_EXCHANGE),
    (3, "corner_extrapolated"): DrivenRun(CORNER3, body_motion, extrapolate=True),
    (3, "chassis_extrapolated"): DrivenRun(CHASSIS3, corner_forces, extrapolate=True),
}


@dataclass
class Model:
    """What the driven runs read from an FMU's modelDescription.xml."""
    token: str  # GUID or instantiationToken
    outputs: list[int]  # value references of the scalar Real / Float64 outputs
    variables: dict[str, int]  # name -> value reference
    model_exchange: bool  # the FMU declares Model Exchange
    states: int  # continuous states (Model Exchange)
    event_indicators: int


def model(fmu: Path, version: int) -> Model:
    if not fmu.is_file():
        pytest.fail(f"{fmu} not found; {BUILD_HINT}")
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    variables, outputs = {}, []
    if version == 2:
        for variable in root.iter("ScalarVariable"):
            vr = int(variable.get("valueReference"))
            variables[variable.get("name")] = vr
            if variable.get("causality") == "output" and variable.find("Real") is not None:
                outputs.append(vr)
        token = root.get("guid")
        derivatives = root.find("ModelStructure/Derivatives")
        states = 0 if derivatives is None else len(derivatives)
        event_indicators = int(root.get("numberOfEventIndicators", "0"))
    else:
        scalars = set()
        for variable in root.find("ModelVariables"):
            vr = int(variable.get("valueReference"))
            variables[variable.get("name")] = vr
            if variable.find("Dimension") is None:
                scalars.add(vr)
            if variable.get("causality") == "output" and variable.tag == "Float64" and vr in scalars:
                outputs.append(vr)
        token = root.get("instantiationToken")
        structure = root.find("ModelStructure")
        derivatives, indicators = structure.findall("ContinuousStateDerivative"), structure.findall("EventIndicator")
        # One state or indicator per element: the harness counts no array's elements.
        for element in derivatives + indicators:
            assert int(element.get("valueReference")) in scalars, f"{fmu.name}: {element.tag} of an array"
        states, event_indicators = len(derivatives), len(indicators)
    assert outputs, f"{fmu.name} declares no Real output"
    return Model(token, outputs, variables, root.find("ModelExchange") is not None, states, event_indicators)


def driven_table(version: int, name: str, spec: DrivenRun, m: Model) -> tuple[list[int], list[int], Path]:
    """The input table of a driven run (the same bytes for every platform):
    the inputs' and the derivatives' value references and the file."""
    times = [k * DRIVEN_STEP for k in range(DRIVEN_STEPS)]
    inputs = sorted(spec.inputs(0.0))
    derivatives = sorted(spec.derivatives(0.0)) if spec.derivatives else []
    values = []
    for t in times:
        u, du = spec.inputs(t), spec.derivatives(t) if spec.derivatives else {}
        values += [u[n] for n in inputs] + [du[n] for n in derivatives]
    path = WORK / "drive" / f"fmi{version}-{name}.bin"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(struct.pack(f"<{len(values)}d", *values))
    return [m.variables[n] for n in inputs], [m.variables[n] for n in derivatives], path


def driven_arguments(version: int, platform: Platform) -> tuple[list[str], dict[str, str]]:
    """The harness's arguments for the driven runs of one FMI version (seven
    per run, the last the mode: `cs`, `cs,VR` with input_extrapolation's
    value reference, or `me,NX,NZ` with the numbers of continuous states
    and event indicators) and the line each run prints
    (a pattern)."""
    arguments, lines = [], {}
    vrs = lambda values: ",".join(map(str, values)) or "-"  # noqa: E731
    for (v, name), spec in DRIVEN_RUNS.items():
        if v == version:
            m = model(spec.fmu, version)
            inputs, derivatives, table = driven_table(version, name, spec, m)
            lines[name] = f"{len(m.outputs)} outputs x {DRIVEN_STEPS} steps"
            mode = CO_SIMULATION
            if spec.extrapolate:
                assert spec.mode == CO_SIMULATION, f"{name}: input_extrapolation is Co-Simulation's"
                mode = f"{CO_SIMULATION},{m.variables['input_extrapolation']}"
            if spec.mode == MODEL_EXCHANGE:
                assert m.model_exchange, f"{spec.fmu.name} declares no ModelExchange"
                assert not derivatives, f"{name}: input derivatives are Co-Simulation only"
                mode = f"{MODEL_EXCHANGE},{m.states},{m.event_indicators}"
                lines[name] += f".*, Model Exchange: {m.states} states, {m.event_indicators} event indicators,"
            arguments += [name, m.token, vrs(m.outputs), vrs(inputs), vrs(derivatives), platform.host_path(table),
                          mode]
    return arguments, lines


def check_driven_runs(stdout: str, prefix: str, lines: dict[str, str]) -> None:
    for name, line in lines.items():
        assert re.search(rf"^{prefix}: drive {name}: {line}", stdout, re.M), stdout


@pytest.fixture(scope="session")
def driven(results, results3):
    """driven(version, run, platform) -> the table of a driven run, which
    the harness of that FMI version writes in its one run on the platform
    (a process start under wine costs seconds)."""

    def get(version: int, name: str, platform: str) -> tuple[list[str], list[list[float]]]:
        return (results if version == 2 else results3)(platform).table(f"drive_{name}.csv")

    return get


def pytest_terminal_summary(terminalreporter):
    if ELF_POLICY:
        terminalreporter.section("Linux libraries: glibc 2.17 floor and NEEDED (elf_policy.py)")
        for line in ELF_POLICY:
            terminalreporter.write_line(line)
    if not OBSERVED:
        return
    terminalreporter.section("largest relative difference to the native linux64 run")
    for platform, files in sorted(OBSERVED.items()):
        for file, (difference, count) in sorted(files.items()):
            verdict = "bit-identical" if difference == 0.0 else f"max {difference:.3g}"
            terminalreporter.write_line(f"{platform:8} {file:18} {int(count):>8} values  {verdict}")
