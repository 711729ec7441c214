"""Model Exchange under the habits of several masters: what each calls and
how well its result agrees with the exact co-simulation.

    .venv/bin/python benches/model_exchange_masters.py [--fmu FMU] [--quick]

Masters: fmpy's CVODE (`simulate_fmu`, rtol 1e-8), fmusim's CVODE (when
`$TDVASS_FMUSIM` names an fmusim binary), fmuCheck's Euler (when
`$TDVASS_FMUCHECK` names fmuCheck.linux64; FMI 2.0 only), an RK4 loop at
1 ms that calls CompletedIntegratorStep every step or never, and scipy's
`solve_ivp` Radau and BDF at rtol 1e-4, 1e-6 and 1e-8, with the FMU's
Jacobian (`jac=` from fmi2GetDirectionalDerivative) and without it
(scipy's own differences). Cases: TDVASS, tau = 0.011 s, the harmonic road
at 2 rad/s over 30 s, and ISO 8608 class C at 20 m/s over 2 s (`--quick`:
3 s and 0.5 s). The error is the largest relative error of the six time
averages (RMS BA, SDD, TDD, J, RMS a_w, the tire-load ratio) at the end
against the co-simulation at tolerance 1e-12. The calls are counted per
run: derivative evaluations, CompletedIntegratorStep, times set before an
earlier one (going back), directional derivatives. Prints a Markdown table
(docs/fmu.md, BENCHMARKS.md).
"""

from __future__ import annotations

import argparse
import csv
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import fmpy
import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests/python"))
from me_master import RK4, ModelExchangeMaster, explicit  # noqa: E402

AVERAGES = ["rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection", "objective",
            "rms_weighted_body_acceleration", "rms_dynamic_tire_load_ratio"]
HARMONIC = {"variant": 3, "tau": 0.011, "road_angular_frequency": 2.0}
ISO_C = {"variant": 3, "tau": 0.011, "road": 2, "road_class": 3, "vehicle_speed": 20.0}


class Counter:
    """Counts a master's calls of one instance (wraps the fmpy object)."""

    NAMES = {"derivatives": ("getDerivatives", "getContinuousStateDerivatives"),
             "completed": ("completedIntegratorStep",),
             "directional": ("getDirectionalDerivative",)}

    def __init__(self, master):
        self.counts = {"derivatives": 0, "completed": 0, "directional": 0, "back": 0}
        self.latest = -np.inf
        fmu = master.fmu
        for key, names in self.NAMES.items():
            for name in names:
                if hasattr(fmu, name):
                    setattr(fmu, name, self.counting(key, getattr(fmu, name)))
        set_time = fmu.setTime

        def timed(t):
            if t < self.latest:
                self.counts["back"] += 1
            self.latest = max(self.latest, t)
            return set_time(t)

        fmu.setTime = timed

    def counting(self, key, function):
        def wrapper(*args, **kwargs):
            self.counts[key] += 1
            return function(*args, **kwargs)

        return wrapper


def exact(fmu, start, duration):
    result = fmpy.simulate_fmu(str(fmu), fmi_type="CoSimulation", start_values=start, stop_time=duration,
                               relative_tolerance=1e-12, output_interval=duration, output=AVERAGES)
    return np.array([result[k][-1] for k in AVERAGES])


def error(values, reference):
    return float(np.max(np.abs(np.asarray(values) / reference - 1)))


def averages(master):
    return np.array([master.read(k) for k in AVERAGES])


def fmpy_cvode(fmu, start, duration):
    """fmpy's simulate_fmu with its CVODE; the calls from its call logger
    (messages `fmi2SetTime(c=..., time=0.01) -> 0`)."""
    calls, latest, back = {}, [-np.inf], [0]

    def trace(message):
        name = message.split("(")[0].strip()
        calls[name] = calls.get(name, 0) + 1
        if name.endswith("SetTime"):
            t = float(message.split("time=")[1].split(")")[0].split(",")[0])
            back[0] += t < latest[0]
            latest[0] = max(latest[0], t)

    interval = 1e-3 if start.get("road") == 2 else 0.01
    result = fmpy.simulate_fmu(str(fmu), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-8,
                               start_values=start, stop_time=duration, output_interval=interval, output=AVERAGES,
                               fmi_call_logger=trace)
    counts = {
        "derivatives": calls.get("fmi2GetDerivatives", 0) + calls.get("fmi3GetContinuousStateDerivatives", 0),
        "completed": sum(v for k, v in calls.items() if k.endswith("CompletedIntegratorStep")),
        "directional": sum(v for k, v in calls.items() if k.endswith("GetDirectionalDerivative")),
        "back": back[0],
    }
    return [result[k][-1] for k in AVERAGES], counts


def fmusim(fmu, start, duration):
    binary = os.environ.get("TDVASS_FMUSIM")
    if not binary:
        return None
    with tempfile.TemporaryDirectory() as work:
        out, calls = Path(work) / "out.csv", Path(work) / "calls.log"
        interval = 1e-3 if start.get("road") == 2 else 0.01
        command = [binary, "--interface-type", "me", "--solver", "cvode", "--stop-time", str(duration),
                   "--output-interval", str(interval), "--tolerance", "1e-8", "--log-fmi-calls",
                   "--fmi-log-file", str(calls), "--output-file", str(out)]
        for key, value in start.items():
            command += ["--start-value", key, str(value)]
        for key in AVERAGES:
            command += ["--output-variable", key]
        subprocess.run(command + [str(fmu)], check=True, capture_output=True)
        with open(out) as fh:
            last = list(csv.DictReader(fh))[-1]
        counts = {"derivatives": 0, "completed": 0, "directional": 0, "back": 0}
        latest = -np.inf
        for line in calls.read_text().splitlines():
            if "GetDerivatives(" in line or "GetContinuousStateDerivatives(" in line:
                counts["derivatives"] += 1
            elif "CompletedIntegratorStep(" in line:
                counts["completed"] += 1
            elif "SetTime(" in line:
                t = float(line.split("time=")[1].split(")")[0].split(",")[0])
                counts["back"] += t < latest
                latest = max(latest, t)
        return [float(last[k]) for k in AVERAGES], counts


def fmucheck(fmu, start, duration):
    binary = os.environ.get("TDVASS_FMUCHECK")
    if not binary or "fmi3" in fmu.name:
        return None
    with tempfile.TemporaryDirectory() as work:
        out = Path(work) / "out.csv"
        # fmuCheck takes no start values: the default experiment's car
        # (TDVASS, tau = 2e-4 s, harmonic 5 rad/s) is compared instead.
        subprocess.run([binary, "-k", "me", "-s", str(duration), "-h", "1e-4", "-o", str(out), str(fmu)],
                       check=True, capture_output=True, cwd=work)
        with open(out) as fh:
            rows = list(csv.reader(fh))
        header = [h.strip('"') for h in rows[0]]
        last = rows[-1]
        values = [float(last[header.index(k)]) for k in AVERAGES]
        steps = round(duration / 1e-4)
        return values, {"derivatives": steps, "completed": steps, "directional": 0, "back": 0}


def rk4(fmu, start, duration, complete):
    master = ModelExchangeMaster(fmu, start)
    counter = Counter(master)
    explicit(master, RK4, duration, 1e-3, complete)
    values = averages(master)
    master.free()
    return values, counter.counts


def scipy_solver(fmu, start, duration, method, rtol, with_jacobian):
    master = ModelExchangeMaster(fmu, start)
    counter = Counter(master)
    master.fmu.getNominalsOfContinuousStates(master.buffer, master.n)
    nominals = np.array(master.buffer[:])
    try:
        solution = solve_ivp(master.derivatives, (0.0, duration), master.states(), method=method, rtol=rtol,
                             atol=rtol * nominals, jac=master.jacobian if with_jacobian else None)
    except Exception as e:  # the FMU refused a state scipy passed
        master.free()
        return f"error: {str(e).splitlines()[0]}", counter.counts
    master.set_point(duration, solution.y[:, -1])
    values = averages(master)
    master.free()
    return values, counter.counts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--fmu", type=Path, default=ROOT / "target/fmu/tdvass.fmu")
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    cases = [("harmonic 2 rad/s", HARMONIC, 3.0 if args.quick else 30.0),
             ("ISO C 20 m/s", ISO_C, 0.5 if args.quick else 2.0)]
    print("| case | master | error | bar | derivatives | CompletedIntegratorStep | back | directional | seconds |")
    print("|---|---|---|---|---|---|---|---|---|")
    for label, start, duration in cases:
        reference = exact(args.fmu, start, duration)
        masters = [("fmpy CVODE rtol 1e-8", 1e-8, lambda: fmpy_cvode(args.fmu, start, duration)),
                   ("fmusim CVODE rtol 1e-8", 1e-8, lambda: fmusim(args.fmu, start, duration)),
                   ("RK4 1 ms, completes every step", None, lambda: rk4(args.fmu, start, duration, True)),
                   ("RK4 1 ms, never completes", None, lambda: rk4(args.fmu, start, duration, False))]
        for method in ("Radau", "BDF"):
            for rtol in (1e-4, 1e-6, 1e-8):
                for jac in (True, False):
                    name = f"scipy {method} rtol {rtol:g}, {'FMU Jacobian' if jac else 'scipy differences'}"
                    masters.append((name, rtol, lambda m=method, r=rtol, j=jac: scipy_solver(args.fmu, start,
                                                                                           duration, m, r, j)))
        for name, rtol, run in masters:
            began = time.perf_counter()
            outcome = run()
            seconds = time.perf_counter() - began
            if outcome is None:
                continue
            values, counts = outcome
            shown = values if isinstance(values, str) else f"{error(values, reference):.1e}"
            bar = f"{100 * rtol:.0e}" if rtol else "-"
            print(f"| {label} | {name} | {shown} | {bar} | {counts['derivatives']} | {counts['completed']} | "
                  f"{counts['back']} | {counts['directional']} | {seconds:.1f} |", flush=True)
        fmucheck_outcome = fmucheck(args.fmu, {}, 3.0)
        if fmucheck_outcome and label.startswith("harmonic"):
            default = exact(args.fmu, {}, 3.0)
            values, counts = fmucheck_outcome
            print(f"| default experiment, 3 s | fmuCheck Euler 0.1 ms | {error(values, default):.1e} | - | "
                  f"{counts['derivatives']} | {counts['completed']} | 0 | 0 | - |")


if __name__ == "__main__":
    main()
