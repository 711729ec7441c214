"""Shared pieces of the cross-master tests: the experiments, the fmpy
reference master, the comparison and the agreement summary.

Every master runs the same experiments with a 1 ms communication step and
reports the outputs at every communication point (not the start). The
reference is fmpy: `fmpy.simulate_fmu` on fmpy's own grid (t_k = k * h), and,
for masters whose clock gives other communication times, a *replay*: fmpy's
`FMU2Slave` driven through exactly the master's communication times (and,
for the input road, the same Jacobi coupling). The FMU's outputs depend on
the communication times only, not on how time is split, so a replay must
agree to the last bit; the differences to fmpy's own grid are explained in
test_libcosim.py and test_ecos.py.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "python"))

from fmu_helpers import OUTPUTS, REPO_ROOT, fmu_path  # noqa: E402,F401

STEP = 1e-3
RTOL = 1e-12
# The running RMS values and J.
TIME_AVERAGES = ["rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection", "objective"]



@dataclass(frozen=True)
class Experiment:
    name: str
    stop_time: float
    start_values: dict = field(default_factory=dict)
    # Start values of a second instance whose `road_displacement` output is
    # connected to the input `x_g` (None: no connection).
    source: dict | None = None
    step_size: float = STEP

    def to_json(self) -> str:
        return json.dumps(
            {
                "name": self.name,
                "stop_time": self.stop_time,
                "step_size": self.step_size,
                "start_values": self.start_values,
                "source": self.source,
                "outputs": OUTPUTS,
            }
        )


EXPERIMENTS = {
    # TDVASS, harmonic road, 15 s: the DefaultExperiment.
    "default": Experiment("default", 15.0),
    # CS on an ISO 8608 class C road, seed 7, 10 s.
    "cs_iso8608": Experiment("cs_iso8608", 10.0, {"variant": 1, "road": 2, "road_class": 3, "road_seed": 7}),
    # The default experiment with the road fed through the input x_g: a
    # second tdvass instance (harmonic road) drives it through a connection
    # road_displacement -> x_g, held over each communication step.
    "input_road": Experiment("input_road", 15.0, {"road": 0}, source={}),
}


def fmpy_grid(stop_time: float, step: float = STEP) -> np.ndarray:
    """fmpy's communication points after the start: k * h (simulateCS)."""
    n = round(stop_time / step)
    return np.arange(1, n + 1) * step


# ------------------------------------------------------------------ reference


def replay(fmu: Path, experiment: Experiment, times, outputs=OUTPUTS, rates=False):
    """fmpy's FMU2Slave stepped through `times` (after the start time 0).

    With a source, it is a Jacobi master like libcosim's and ecos's: after
    every step the source's road_displacement at the new time is set as the
    sink's x_g for the next step (x_g is 0 = the source's road at t = 0
    before the first). With `rates`, it returns the outputs' first
    derivatives (fmi2GetRealOutputDerivatives) too: (rows, rates).
    """
    from fmpy import extract, read_model_description

    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    kind = {v.name: v.type for v in md.modelVariables}
    with tempfile.TemporaryDirectory(prefix="tdvass-interop-") as unzipdir:
        extract(str(fmu), unzipdir=unzipdir)
        return _replay(md, vr, kind, unzipdir, experiment, times, outputs, rates)


def grid_reference(fmu: Path, experiment: Experiment, master_times) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """fmpy's FMU2Slave on fmpy's grid (k * h): (times, rows, rates).

    For a fed road, the sink gets the x_g values the master's connection
    gave it: the source's road at the master's own times. The master's
    clock then differs from the grid only where the sink is stepped, which
    is what `drift_explained` allows for.
    """
    times = fmpy_grid(experiment.stop_time, experiment.step_size)
    inputs = None
    if experiment.source is not None:
        source = Experiment("source", experiment.stop_time, experiment.source)
        road = replay(fmu, source, master_times, outputs=["road_displacement"])[:, 0]
        inputs = np.concatenate([[0.0], road[:-1]])
    sink = replace(experiment, source=None)
    from fmpy import extract, read_model_description

    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    kind = {v.name: v.type for v in md.modelVariables}
    with tempfile.TemporaryDirectory(prefix="tdvass-interop-") as unzipdir:
        extract(str(fmu), unzipdir=unzipdir)
        rows, rates = _replay(md, vr, kind, unzipdir, sink, times, OUTPUTS, True, inputs)
    return times, rows, rates


def _replay(md, vr, kind, unzipdir, experiment, times, outputs, with_rates=False, inputs=None):
    from fmpy.fmi2 import FMU2Slave

    stop = float(times[-1])

    def start(name, values):
        slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier="tdvass", instanceName=name)
        slave.instantiate()
        slave.setupExperiment(startTime=0.0, stopTime=stop)
        for key, value in values.items():
            if kind[key] == "Integer":
                slave.setInteger([vr[key]], [int(value)])
            else:
                slave.setReal([vr[key]], [float(value)])
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        return slave

    sink = start("sink", experiment.start_values)
    source = start("source", experiment.source) if experiment.source is not None else None
    out_vrs = [vr[n] for n in outputs]
    rows = np.empty((len(times), len(outputs)))
    rates = np.empty((len(times), len(outputs)))
    t = 0.0
    try:
        for k, t_next in enumerate(times):
            t_next = float(t_next)
            if source is not None:
                sink.setReal([vr["x_g"]], source.getReal([vr["road_displacement"]]))
                source.doStep(currentCommunicationPoint=t, communicationStepSize=t_next - t)
            elif inputs is not None:
                sink.setReal([vr["x_g"]], [float(inputs[k])])
            sink.doStep(currentCommunicationPoint=t, communicationStepSize=t_next - t)
            rows[k] = sink.getReal(out_vrs)
            if with_rates:
                rates[k] = sink.getRealOutputDerivatives(out_vrs, [1] * len(out_vrs))
            t = t_next
    finally:
        for slave in (sink, source):
            if slave is not None:
                slave.terminate()
                slave.freeInstance()  # fmpy's: also dlcloses the library
    return (rows, rates) if with_rates else rows


def simulate_fmu(fmu: Path, experiment: Experiment, outputs=OUTPUTS) -> tuple[np.ndarray, np.ndarray]:
    """fmpy.simulate_fmu at the experiment's output interval: (times, rows) after the start.

    The input-road experiment gets fmpy's input table instead of a
    connection: the source's road at fmpy's own grid (from a replay of the
    source alone), which fmpy applies at each communication point.
    """
    import fmpy

    input_table = None
    if experiment.source is not None:
        input_table = input_road_table(fmu, experiment)
    result = fmpy.simulate_fmu(
        str(fmu),
        start_values=dict(experiment.start_values),
        stop_time=experiment.stop_time,
        output_interval=experiment.step_size,
        input=input_table,
        output=outputs,
    )
    times = result["time"][1:]
    rows = np.column_stack([result[n][1:] for n in outputs])
    return times, rows


def input_road_table(fmu: Path, experiment: Experiment) -> np.ndarray:
    """(time, x_g) at 0 and fmpy's grid: the source instance's road_displacement."""
    source = Experiment("source", experiment.stop_time, experiment.source or {})
    times = fmpy_grid(experiment.stop_time, experiment.step_size)
    road = replay(fmu, source, times, outputs=["road_displacement"])[:, 0]
    table = np.zeros(len(times) + 1, dtype=[("time", np.double), ("x_g", np.double)])
    table["time"][1:] = times
    table["x_g"][1:] = road
    return table


# ------------------------------------------------------------------ FMI 3.0 reference


def fmi3_path() -> Path:
    """The FMI 3.0 FMU built next to the FMI 2.0 one: target/fmu/tdvass-fmi3.fmu."""
    return fmu_path().with_name("tdvass-fmi3.fmu")


# The corner's FMUs (Co-Simulation and Model Exchange), built next to the quarter car's:
# file name -> FMI version.
CORNER_FMUS = {"tdvass-corner.fmu": "2.0", "tdvass-corner-fmi3.fmu": "3.0"}

# The chassis's FMUs (Co-Simulation and Model Exchange), likewise.
CHASSIS_FMUS = {"tdvass-chassis.fmu": "2.0", "tdvass-chassis-fmi3.fmu": "3.0"}


def replay3(fmu: Path, experiment: Experiment, times, outputs=OUTPUTS) -> np.ndarray:
    """fmpy's FMU3Slave (FMI 3.0 FMU) stepped through `times` after 0, with
    the experiment's start values (Enumerations by their integer codes) and,
    for a source, the same Jacobi connection as `replay`."""
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Slave

    md = read_model_description(str(fmu))
    var = {v.name: v for v in md.modelVariables}
    setters = {"Enumeration": "setInt64", "Int64": "setInt64", "Int32": "setInt32", "Float64": "setFloat64"}
    stop = float(times[-1])
    with tempfile.TemporaryDirectory(prefix="tdvass-interop-") as unzipdir:
        extract(str(fmu), unzipdir=unzipdir)

        def start(name, values):
            slave = FMU3Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier="tdvass", instanceName=name)
            slave.instantiate()
            for key, value in values.items():
                getattr(slave, setters[var[key].type])([var[key].valueReference], [value])
            slave.enterInitializationMode(startTime=0.0, stopTime=stop)
            slave.exitInitializationMode()
            return slave

        sink = start("sink", experiment.start_values)
        source = start("source", experiment.source) if experiment.source is not None else None
        out_vrs = [var[n].valueReference for n in outputs]
        x_g, road = var["x_g"].valueReference, var["road_displacement"].valueReference
        rows = np.empty((len(times), len(outputs)))
        t = 0.0
        try:
            for k, t_next in enumerate(times):
                t_next = float(t_next)
                if source is not None:
                    sink.setFloat64([x_g], source.getFloat64([road]))
                    _, terminate, early, last = source.doStep(t, t_next - t)
                    assert not (terminate or early) and last == t_next, (terminate, early, last)
                _, terminate, early, last = sink.doStep(t, t_next - t)
                assert not (terminate or early) and last == t_next, (terminate, early, last)
                rows[k] = sink.getFloat64(out_vrs)
                t = t_next
        finally:
            for slave in (sink, source):
                if slave is not None:
                    slave.terminate()
                    slave.freeInstance()
    return rows


def simulate_fmu3(fmu: Path, experiment: Experiment, outputs=OUTPUTS) -> tuple[np.ndarray, np.ndarray]:
    """`fmpy.simulate_fmu` of the FMI 3.0 FMU as Co-Simulation, as
    `simulate_fmu`: (times, rows) after the start; the input road is the
    FMI 3.0 source's road_displacement on fmpy's grid, as an input table."""
    import fmpy

    input_table = None
    if experiment.source is not None:
        source = Experiment("source", experiment.stop_time, experiment.source)
        times = fmpy_grid(experiment.stop_time, experiment.step_size)
        input_table = np.zeros(len(times) + 1, dtype=[("time", np.double), ("x_g", np.double)])
        input_table["time"][1:] = times
        input_table["x_g"][1:] = replay3(fmu, source, times, outputs=["road_displacement"])[:, 0]
    result = fmpy.simulate_fmu(
        str(fmu),
        fmi_type="CoSimulation",
        start_values=dict(experiment.start_values),
        stop_time=experiment.stop_time,
        output_interval=experiment.step_size,
        input=input_table,
        output=outputs,
    )
    return result["time"][1:], np.column_stack([result[n][1:] for n in outputs])


# ------------------------------------------------------------------ comparison


@dataclass
class Agreement:
    """How two runs (rows: communication points, columns: OUTPUTS) agree."""

    max_rel: dict  # per output: max |a - b| / max(|a|, |b|) over the points
    max_scaled: dict  # per output: max |a - b| / max |reference|
    differing: dict  # per output: number of points that differ at all

    @property
    def identical(self) -> bool:
        return not any(self.differing.values())

    def worst(self, names=None) -> float:
        names = names if names is not None else list(self.max_rel)
        return max(self.max_rel[n] for n in names)

    def worst_scaled(self, names=None) -> float:
        names = names if names is not None else list(self.max_scaled)
        return max(self.max_scaled[n] for n in names)

    def describe(self) -> str:
        if self.identical:
            return "bit-identical"
        worst = max(self.max_rel, key=self.max_rel.get)
        scaled = max(self.max_scaled, key=self.max_scaled.get)
        differ = [n for n in self.differing if self.differing[n]]
        return (f"max rel {self.max_rel[worst]:.1e} ({worst}), max peak-scaled "
                f"{self.max_scaled[scaled]:.1e} ({scaled}); {len(differ)}/{len(self.differing)} outputs differ"
                + ("" if len(differ) == len(self.differing) else f": {', '.join(differ)}"))


def agreement(rows: np.ndarray, reference: np.ndarray, names=OUTPUTS) -> Agreement:
    rows, reference = np.asarray(rows, dtype=float), np.asarray(reference, dtype=float)
    assert rows.shape == reference.shape, (rows.shape, reference.shape)
    assert np.all(np.isfinite(rows)), "non-finite output"
    max_rel, max_scaled, differing = {}, {}, {}
    for j, name in enumerate(names):
        a, b = rows[:, j], reference[:, j]
        diff = np.abs(a - b)
        scale = np.maximum(np.abs(a), np.abs(b))
        rel = np.divide(diff, scale, out=np.zeros_like(diff), where=scale > 0)
        peak = np.max(np.abs(b))
        max_rel[name] = float(rel.max())
        max_scaled[name] = float(diff.max() / peak) if peak > 0 else float(diff.max())
        differing[name] = int(np.count_nonzero(diff))
    return Agreement(max_rel, max_scaled, differing)


def drift_explained(rows, times, reference, reference_times, rates, what=""):
    """Checks a master's run against fmpy's grid: every output at every
    point may differ only by the clock drift times its rate of change
    (twice, for the rate's own change), plus 1e-12 of its peak. Returns the
    Agreement and the largest drift."""
    drift = np.abs(np.asarray(times) - np.asarray(reference_times))
    difference = np.abs(np.asarray(rows) - np.asarray(reference))
    peak = np.abs(reference).max(axis=0)
    allowed = 2.0 * drift[:, None] * np.abs(rates) + RTOL * peak
    excess = difference - allowed
    worst = int(np.argmax(excess.max(axis=0)))
    k = int(np.argmax(excess[:, worst]))
    assert (excess <= 0.0).all(), (
        f"{what}: {OUTPUTS[worst]} at t = {times[k]} differs by {difference[k, worst]:.3e}, "
        f"more than the drift {drift[k]:.1e} s explains ({allowed[k, worst]:.3e})"
    )
    return agreement(rows, reference), float(drift.max())


def assert_agrees(rows, reference, rtol=RTOL, what=""):
    result = agreement(rows, reference)
    assert result.worst() <= rtol, f"{what}: {result.describe()}"
    return result


# ------------------------------------------------------------------ summary

SUMMARY_FILE = Path(os.environ.get("TDVASS_INTEROP_SUMMARY", REPO_ROOT / "target" / "interop" / "summary.json"))
_summary: list[dict] = []


def record(master: str, experiment: str, against: str, result: Agreement | str, note: str = ""):
    """One line of the agreement table printed at the end of the session."""
    text = result if isinstance(result, str) else result.describe()
    _summary.append({"master": master, "experiment": experiment, "against": against,
                     "agreement": text, "note": note})


def summary_lines() -> list[str]:
    lines = []
    if not _summary:
        return lines
    width = max(len(row["master"]) for row in _summary)
    for row in _summary:
        note = f" [{row['note']}]" if row["note"] else ""
        lines.append(f"{row['master']:<{width}}  {row['experiment']:<11} vs {row['against']:<23} "
                     f"{row['agreement']}{note}")
    return lines


def write_summary():
    if not _summary:
        return
    SUMMARY_FILE.parent.mkdir(parents=True, exist_ok=True)
    SUMMARY_FILE.write_text(json.dumps(_summary, indent=1))


# ------------------------------------------------------------------ masters in a subprocess


def run_master(master: str, fmu: Path, experiment: Experiment, out_dir: Path, timeout=300):
    """run_master.py in a fresh process: (times, rows, version, variables)."""
    import signal
    import subprocess

    out = Path(out_dir) / f"{master}-{experiment.name}.npz"
    done = subprocess.run(
        [sys.executable, str(HERE / "run_master.py"), master, str(fmu), experiment.to_json(), str(out)],
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    if done.returncode < 0:
        raise AssertionError(
            f"{master} crashed with {signal.Signals(-done.returncode).name}\n{done.stdout}\n{done.stderr}"
        )
    assert done.returncode == 0, f"{master} failed\n{done.stdout}\n{done.stderr}"
    data = np.load(out)
    return data["times"], data["rows"], str(data["version"]), json.loads(str(data["variables"]))


def split(result: Agreement, names) -> tuple[float, float]:
    """(worst pointwise relative, worst peak-scaled) over `names`."""
    return result.worst(names), result.worst_scaled(names)
