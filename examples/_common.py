"""Helpers shared by the example scripts (not an example itself).

- where the `tdvass` binary and the FMU are (``TDVASS_BIN``, ``TDVASS_FMU``),
- the common command line (``--quick``, ``--out DIR``),
- the paper's printed values (Tables 1-3, section 3.3, section 4.2),
- running the FMU step by step with fmpy (``FmuRunner``).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent

# ---------------------------------------------------------------------------
# The paper's printed values
# ---------------------------------------------------------------------------
VARIANTS = {"cs": 1, "pvass": 2, "tdvass": 3}
LABELS = {"cs": "CS", "pvass": "PVASS", "tdvass": "TDVASS"}
COLORS = {"cs": "tab:blue", "pvass": "tab:orange", "tdvass": "tab:green"}

# Table 1 (and the controller gains of section 4.2)
TABLE1 = {"m_s": 345.0, "m_h": 4.05, "m_t": 40.5, "k_s": 16000.0, "k_h": 6444.0,
          "k_t": 190000.0, "c_s": 1500.0, "c_h": 348.0}
G1, TAU1 = 5386.0, 2e-4      # harmonic road (Table 2)
G2, TAU2 = 2528.0, 1.28e-4   # random road (Table 3, Fig. 14)

# RMS values: BA (m/s^2), SDD (m), TDD (mm)
TABLE2 = {"cs": (1.6081, 0.0312, 3.1109), "pvass": (0.9715, 0.0693, 1.6606),
          "tdvass": (0.3068, 0.0388, 0.6251)}
TABLE3 = {"cs": (0.3184, 0.0047, 0.6399), "pvass": (0.1512, 0.0105, 0.5607),
          "tdvass": (0.1014, 0.0073, 0.5289)}
METRICS = ("BA (m/s²)", "SDD (m)", "TDD (mm)")
METRICS_ASCII = ("BA (m/s^2)", "SDD (m)", "TDD (mm)")

# Section 3.3: verification points (g in N/m, tau in s) and the paper's verdict
STABILITY_POINTS = [
    ("A1*", 40000.0, 0.03, True),
    ("A2*", -40000.0, 0.11, False),
    ("A3*", 40000.0, 0.15, False),
    ("A4*", -40000.0, 0.25, True),
    ("A5*", 40000.0, 0.3, True),
    ("A6*", -40000.0, 0.4, False),
]

# The field metrics the FMU computes besides the paper's RMS values (running
# outputs, read at the end of a run; the scripts' CSV columns have the same
# names): ISO 2631-1 W_k-weighted RMS body acceleration a_w, vibration dose
# value, RMS dynamic tire load / static load, time without tire contact, max |SDD|
FIELD_METRICS = {
    "rms_weighted_body_acceleration": "a_w (m/s^2)",
    "vibration_dose_value": "VDV (m/s^1.75)",
    "rms_dynamic_tire_load_ratio": "tire load ratio",
    "contact_loss_time": "contact loss (s)",
    "max_suspension_deflection": "max |SDD| (m)",
}
FIELD_OUTPUTS = list(FIELD_METRICS)
TIRE_LOAD_RATIO_LIMIT = 1.0 / 3.0  # RMS dynamic tire load <= static / 3: contact kept at 3 sigma
G0 = 9.80665  # standard gravity, m/s^2

# ISO 2631-1 (Annex C) comfort reactions by the lower bound of a_w (m/s^2); the
# standard's bands overlap, a value is given the harshest band it reaches
COMFORT_BANDS = [(2.0, "extremely uncomfortable"), (1.25, "very uncomfortable"), (0.8, "uncomfortable"),
                 (0.5, "fairly uncomfortable"), (0.315, "a little uncomfortable")]


def comfort_reaction(a_w: float) -> str:
    """The ISO 2631-1 comfort reaction to a weighted RMS acceleration a_w (m/s^2)."""
    return next((name for lower, name in COMFORT_BANDS if a_w >= lower), "not uncomfortable")


def static_deflection(variant: str, k_h: float = TABLE1["k_h"], k_s: float = TABLE1["k_s"]) -> float:
    """Static deflection (m) of the springs between body and wheel under the weight above
    them: m_s g0/k_s + (m_s + m_h) g0/k_h (CS: m_s g0/k_s)."""
    m_s, m_h = TABLE1["m_s"], TABLE1["m_h"]
    sag = m_s * G0 / k_s
    return sag if variant == "cs" else sag + (m_s + m_h) * G0 / k_h


# ISO 8608 roughness Gq(n0) by class, m^3
ISO_GQ = {c: 16e-6 * 4 ** i for i, c in enumerate("ABCDEFGH")}
N0 = 0.1  # reference spatial frequency, 1/m


# ---------------------------------------------------------------------------
# Command line, files
# ---------------------------------------------------------------------------
class _HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Appends "(default: ...)" where the help text does not already say it."""

    def _get_help_string(self, action):
        text = action.help or ""
        if "default" in text or any(action.default is d for d in (None, False, argparse.SUPPRESS)):
            return text
        return text + " (default: %(default)s)"


def parser(description: str) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=description, formatter_class=_HelpFormatter)
    p.add_argument("--quick", action="store_true",
                   help="small sizes (a few seconds); used by CI")
    p.add_argument("--out", default="out", type=Path, help="output directory")
    return p


def prepare_out(out: Path) -> Path:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    return out


def write_summary(out: Path, name: str, text: str) -> Path:
    path = Path(out) / f"{name}.txt"
    path.write_text(text if text.endswith("\n") else text + "\n", encoding="utf-8")
    print(text)
    print(f"wrote {path}")
    return path


def save_figure(fig, out: Path, name: str) -> Path:
    path = Path(out) / f"{name}.png"
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")
    return path


# ---------------------------------------------------------------------------
# The CLI
# ---------------------------------------------------------------------------
def target_dir() -> Path:
    """Cargo's target directory: $CARGO_TARGET_DIR, else <repo>/target."""
    env = os.environ.get("CARGO_TARGET_DIR")
    path = Path(env) if env else ROOT / "target"
    return path if path.is_absolute() else ROOT / path


def tdvass_bin() -> str:
    """The `tdvass` executable: $TDVASS_BIN, else <target>/release/tdvass."""
    path = os.environ.get("TDVASS_BIN") or str(target_dir() / "release" / "tdvass")
    if not (os.path.isfile(path) and os.access(path, os.X_OK)):
        found = shutil.which(path)
        if found is None:
            sys.exit(f"tdvass binary not found at {path}: run `cargo build --release` "
                     "in the repository or set TDVASS_BIN")
        path = found
    return path


def cli(*args, json_output: bool = True, check: bool = True):
    """Runs `tdvass ARGS` and returns its parsed JSON (or its stdout)."""
    cmd = [tdvass_bin(), *[str(a) for a in args]]
    if json_output:
        cmd.append("--json")
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if check and proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}): {proc.stderr.strip()}")
    return json.loads(proc.stdout) if json_output else proc.stdout


def params_flags(**params) -> list[str]:
    """{'k_h': 6444} -> ['--k-h', '6444'] (flags are named as the FMU parameters)."""
    flags = []
    for name, value in params.items():
        flags += [f"--{name.replace('_', '-')}", repr(value) if isinstance(value, float) else str(value)]
    return flags


def read_csv(path_or_text, from_text: bool = False) -> dict[str, np.ndarray]:
    import io

    src = io.StringIO(path_or_text) if from_text else path_or_text
    data = np.genfromtxt(src, delimiter=",", names=True)
    return {name: np.asarray(data[name]) for name in data.dtype.names}


# ---------------------------------------------------------------------------
# The FMU
# ---------------------------------------------------------------------------
def fmu_path() -> str:
    """The FMU: $TDVASS_FMU, else <target>/fmu/tdvass.fmu."""
    path = os.environ.get("TDVASS_FMU") or str(target_dir() / "fmu" / "tdvass.fmu")
    if not os.path.isfile(path):
        sys.exit(f"FMU not found at {path}: run `cargo run --release -p fmu-build` "
                 "in the repository or set TDVASS_FMU")
    return path


class FmuRunner:
    """Runs the tdvass FMU with fmpy's FMU2Slave, one instance reused for many runs.

    ``run(params, stop, step, outputs)`` instantiates (or resets) the slave,
    sets the start values, steps to ``stop`` and returns a dict of arrays
    (``time`` plus every requested output) and ``error`` (None, or the
    message of a failed doStep: the arrays then end at the last good step).
    """

    def __init__(self, path: str | None = None, unzipdir: str | None = None):
        from fmpy import extract, read_model_description

        self.path = path or fmu_path()
        self.md = read_model_description(self.path)
        self._own_dir = unzipdir is None
        self.unzipdir = unzipdir or extract(self.path)
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.slave = None
        self._instantiated = False

    # -- helpers -----------------------------------------------------------
    def vr(self, name: str) -> int:
        return self.vars[name].valueReference

    def has(self, name: str) -> bool:
        return name in self.vars

    def _set(self, name: str, value) -> None:
        v = self.vars[name]
        if v.type == "Real":
            self.slave.setReal([v.valueReference], [float(value)])
        elif v.type in ("Integer", "Enumeration"):
            self.slave.setInteger([v.valueReference], [int(value)])
        elif v.type == "Boolean":
            self.slave.setBoolean([v.valueReference], [bool(value)])
        else:
            raise TypeError(f"cannot set {name} of type {v.type}")

    def get(self, name: str):
        v = self.vars[name]
        if v.type == "Real":
            return self.slave.getReal([v.valueReference])[0]
        if v.type == "Boolean":
            return self.slave.getBoolean([v.valueReference])[0]
        return self.slave.getInteger([v.valueReference])[0]

    # -- running -------------------------------------------------------------
    def run(self, params: dict, stop: float, step: float, outputs: list[str],
            after_init=None) -> dict:
        from fmpy.fmi2 import FMU2Slave

        if self.slave is not None and self._instantiated:
            try:
                self.slave.reset()
            except Exception:
                self._drop()
        if self.slave is None:
            self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipdir,
                                   modelIdentifier=self.md.coSimulation.modelIdentifier,
                                   instanceName="tdvass")
            self.slave.instantiate()
            self._instantiated = True
        for name, value in params.items():
            self._set(name, value)
        self.slave.setupExperiment(startTime=0.0, stopTime=stop)
        self.slave.enterInitializationMode()
        self.slave.exitInitializationMode()
        extra = after_init(self) if after_init else None

        vrs = [self.vr(n) for n in outputs]
        n = int(round(stop / step))
        rows = np.full((n + 1, len(outputs)), np.nan)
        times = np.arange(n + 1) * step
        rows[0] = self.slave.getReal(vrs)
        last, error = 0, None
        for k in range(n):
            try:
                self.slave.doStep(currentCommunicationPoint=k * step, communicationStepSize=step)
            except Exception as exc:  # fmpy raises on fmi2Discard / fmi2Error
                error = str(exc) or type(exc).__name__
                break
            rows[k + 1] = self.slave.getReal(vrs)
            last = k + 1
        if error is None:
            self.slave.terminate()
        else:
            # A diverged run is discarded (fmi2Discard): the FMU stays at the last good
            # internal node, whose outputs can still be read; then terminate and reset.
            try:
                t_last = self.slave.getRealStatus(2)  # fmi2LastSuccessfulTime
                if t_last > times[last] and last + 1 < times.size:
                    times[last + 1] = t_last
                    rows[last + 1] = self.slave.getReal(vrs)
                    last += 1
                self.slave.terminate()
            except Exception:
                self._drop()  # after fmi2Error the instance is unusable
        result = {"time": times[: last + 1], "error": error, "extra": extra}
        for i, name in enumerate(outputs):
            result[name] = rows[: last + 1, i]
        return result

    def _drop(self) -> None:
        if self.slave is not None and self._instantiated:
            try:
                self.slave.freeInstance()
            except Exception:
                pass
        self.slave = None
        self._instantiated = False

    def close(self) -> None:
        self._drop()
        if self._own_dir:
            shutil.rmtree(self.unzipdir, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def rms_row(result: dict) -> tuple[float, float, float]:
    """(BA m/s^2, SDD m, TDD mm) from the FMU's running RMS outputs at the end."""
    return (float(result["rms_body_acceleration"][-1]),
            float(result["rms_suspension_deflection"][-1]),
            1e3 * float(result["rms_tire_deflection"][-1]))


def field_row(result: dict) -> tuple[float, ...]:
    """The FIELD_METRICS values from the FMU's running outputs at the end."""
    return tuple(float(result[name][-1]) for name in FIELD_OUTPUTS)


def pct(ours: float, paper: float) -> str:
    d = round(100.0 * (ours - paper) / paper, 1)
    return f"{d + 0.0:+.1f} %"  # + 0.0 turns -0.0 into 0.0
