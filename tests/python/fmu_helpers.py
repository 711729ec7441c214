"""Helpers shared by the fmpy tests and by the fresh-process worker.

Run as a script, this module continues a serialized FMU state in a fresh
process (see ``test_serialized_state_continues_in_a_fresh_process``)::

    python fmu_helpers.py continue FMU_DIR STATE_FILE T_FROM T_TO STEP
    python fmu_helpers.py continue-accumulated FMU_DIR STATE_FILE T_FROM STEPS STEP

The second form steps like most masters do: `STEPS` steps of `STEP` from
`T_FROM` with the time accumulated (`t += STEP`).
"""

from __future__ import annotations

import json
import os
import sys
from ctypes import byref
from pathlib import Path

from fmpy import calloc, free, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.logging import addLoggerProxy

REPO_ROOT = Path(__file__).resolve().parents[2]

STATES = ["x_s", "v_s", "x_h", "v_h", "x_t", "v_t"]
OUTPUTS = STATES + [
    "body_acceleration",
    "suspension_deflection",
    "tire_deflection",
    "road_displacement",
    "control_force",
    "rms_body_acceleration",
    "rms_suspension_deflection",
    "rms_tire_deflection",
    "objective",
]
RMS = ["rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection"]


def fmu_path() -> Path:
    """The built FMU: $TDVASS_FMU, or target/fmu/tdvass.fmu of the repository."""
    override = os.environ.get("TDVASS_FMU")
    if override:
        return Path(override)
    target = os.environ.get("CARGO_TARGET_DIR")
    target_dir = Path(target) if target else REPO_ROOT / "target"
    if not target_dir.is_absolute():
        target_dir = REPO_ROOT / target_dir
    return target_dir / "fmu" / "tdvass.fmu"


def corner_path() -> Path:
    """The corner's FMI 2.0 FMU, next to the quarter car's: tdvass-corner.fmu."""
    return fmu_path().with_name("tdvass-corner.fmu")


def corner_fmi3_path() -> Path:
    """The corner's FMI 3.0 FMU, next to the quarter car's: tdvass-corner-fmi3.fmu."""
    return fmu_path().with_name("tdvass-corner-fmi3.fmu")


def chassis_path() -> Path:
    """The chassis's FMI 2.0 FMU, next to the quarter car's: tdvass-chassis.fmu."""
    return fmu_path().with_name("tdvass-chassis.fmu")


def chassis_fmi3_path() -> Path:
    """The chassis's FMI 3.0 FMU, next to the quarter car's: tdvass-chassis-fmi3.fmu."""
    return fmu_path().with_name("tdvass-chassis-fmi3.fmu")


_STATUS = ["OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING"]
_captures: dict = {}


def _dispatch(environment, _name, status, category, message):
    """The one Python logger behind fmpy's native proxy.

    fmpy's proxy (it formats the printf-style message) keeps a single global
    target, so every capture shares this function and is found through its
    componentEnvironment. Instances with other callbacks (fmpy's defaults)
    are printed like fmpy prints them.
    """
    entry = (status, (category or b"").decode(), (message or b"").decode(errors="replace"))
    capture = _captures.get(environment or 0)
    if capture is None:
        print(f"[{_STATUS[status] if 0 <= status < len(_STATUS) else status}] {entry[2]}")
    else:
        capture.messages.append(entry)
        if capture.echo:
            print(entry)


# Module-level, so it outlives every instance that may still log through it.
_DISPATCH = fmi2CallbackLoggerTYPE(_dispatch)
_ALLOCATE = fmi2CallbackAllocateMemoryTYPE(calloc)
_FREE = fmi2CallbackFreeMemoryTYPE(free)


class LogCapture:
    """fmi2CallbackFunctions whose logger records (status, category, message)."""

    def __init__(self, echo: bool = False):
        self.messages: list[tuple[int, str, str]] = []
        self.echo = echo
        key = len(_captures) + 1
        _captures[key] = self  # kept for the process lifetime: instances may log late
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = _DISPATCH
        self.callbacks.allocateMemory = _ALLOCATE
        self.callbacks.freeMemory = _FREE
        self.callbacks.componentEnvironment = key
        # fmpy's native proxy formats the printf-style message first.
        addLoggerProxy(byref(self.callbacks))

    def last(self) -> tuple[int, str, str]:
        return self.messages[-1]

    def text(self) -> str:
        return "\n".join(m for _, _, m in self.messages)


class Slave:
    """An FMU2Slave with name-based access and its log."""

    def __init__(self, unzipdir, model_description, name="tdvass", guid=None, logging_on=False):
        self.md = model_description
        self.vr = {v.name: v.valueReference for v in model_description.modelVariables}
        self.log = LogCapture()
        self.fmu = FMU2Slave(
            guid=guid if guid is not None else model_description.guid,
            unzipDirectory=str(unzipdir),
            modelIdentifier=model_description.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate(callbacks=self.log.callbacks, loggingOn=logging_on)
        self.time = 0.0

    def start(self, stop_time=None, start_time=0.0, **values):
        """Set up, set parameter values (ints for Integer variables) and initialize."""
        self.fmu.setupExperiment(startTime=start_time, stopTime=stop_time)
        self.set(**values)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.time = start_time
        return self

    def set(self, **values):
        for name, value in values.items():
            if isinstance(value, bool):
                self.fmu.setBoolean([self.vr[name]], [value])
            elif isinstance(value, int):
                self.fmu.setInteger([self.vr[name]], [value])
            else:
                self.fmu.setReal([self.vr[name]], [float(value)])

    def get(self, names=OUTPUTS) -> list[float]:
        return self.fmu.getReal([self.vr[n] for n in names])

    def step_to(self, t: float):
        self.fmu.doStep(currentCommunicationPoint=self.time, communicationStepSize=t - self.time)
        self.time = t

    def run(self, times) -> list[list[float]]:
        """Steps through `times`, returning the outputs at each."""
        out = []
        for t in times:
            self.step_to(t)
            out.append(self.get())
        return out

    def free(self):
        if self.fmu is not None:
            self.fmu.freeInstance()
            self.fmu = None


def grid(t_from: float, t_to: float, step: float) -> list[float]:
    n = round((t_to - t_from) / step)
    return [t_from + k * step for k in range(1, n + 1)]


def accumulated_times(t_from: float, steps: int, step: float) -> list[float]:
    """`steps` communication points reached by `t += step` from `t_from`."""
    times, t = [], t_from
    for _ in range(steps):
        t += step
        times.append(t)
    return times


def continue_in_this_process(fmu_dir, state_file, t_from, times):
    """Worker: restore a serialized state in a new instance and continue
    through `times`."""
    md = read_model_description(fmu_dir)
    slave = Slave(fmu_dir, md, name="worker")
    state = slave.fmu.deSerializeFMUstate(Path(state_file).read_bytes())
    slave.fmu.setFMUstate(state)
    slave.fmu.freeFMUstate(state)
    slave.time = t_from
    rows = slave.run(times)
    slave.fmu.terminate()
    slave.free()
    return [[v.hex() for v in row] for row in rows]


if __name__ == "__main__":
    if len(sys.argv) == 7 and sys.argv[1] in ("continue", "continue-accumulated"):
        _, mode, fmu_dir, state_file, t_from, until, step = sys.argv
        t_from, step = float(t_from), float(step)
        if mode == "continue":
            times = grid(t_from, float(until), step)
        else:
            times = accumulated_times(t_from, int(until), step)
        print(json.dumps(continue_in_this_process(fmu_dir, state_file, t_from, times)))
    else:
        sys.exit(__doc__)
