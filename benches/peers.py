#!/usr/bin/env python3
"""What a Python user would do instead of tdvass: the paper's 15 s TDVASS
harmonic case solved by Python DDE tools, each with its error against a
fine-step reference and its wall time next to tdvass's.

The case (paper, Table 1 and section 5.1): TDVASS with g = 5386 N/m,
tau = 2e-4 s, road x_g = 0.05 sin 5t, from rest (constant zero history),
15 s:  dX/dt = A X + b x_t(t - tau) + e x_g(t).

Solvers:
  tdvass        the CLI (`tdvass simulate`), precise integration at the
                default tolerance 1e-6 (the step follows from it)
  scipy RK45    `scipy.integrate.RK45` stepped by hand with max_step = tau
                and the delayed x_t read from the dense output of earlier
                steps (method of steps with an interpolated history)
  ddeint        the PyPI `ddeint` (odeint/vode underneath, linearly
                interpolated history on the output grid)
  JiTCDDE       the PyPI `jitcdde` (compiled C, adaptive Bogacki-Shampine,
                cubic Hermite history), if it installs

Errors are measured on a common 1 ms output grid against the reference
`tdvass simulate --max-internal-step 2e-6` (fourth order in the step, so its
own error is ~1e-8 of the default's); the scipy run at rtol 1e-12 is an
independent check of that reference. "state error" is
max_t max_i |X_i - X_ref,i| / max |X_ref,i|; the RMS errors are relative.
All RMS values here come from the same 1 ms samples (tdvass's own --json
RMS is sampled on its internal grid instead).

Usage: benches/peers.py [--smoke] [--tdvass PATH] [--json FILE]
--smoke: 0.5 s of simulated time, one repetition, no timing claims (CI).
"""

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent

# Table 1 and the harmonic-road controller (g1, tau1).
M_S, M_H, M_T = 345.0, 4.05, 40.5
K_S, K_H, K_T = 16000.0, 6444.0, 190000.0
C_S, C_H = 1500.0, 348.0
G, TAU = 5386.0, 2e-4
AMPLITUDE, OMEGA = 0.05, 5.0
REFERENCE_STEP = 2e-6
SAMPLE = 1e-3


def plant():
    """A, b (with the gain), e of Eq. (2) for TDVASS, state
    [x_s, v_s, x_h, v_h, x_t, v_t]."""
    a = np.zeros((6, 6))
    a[0, 1] = 1.0
    a[2, 3] = 1.0
    a[4, 5] = 1.0
    a[1, 0] = -K_S / M_S
    a[1, 1] = -C_S / M_S
    a[1, 2] = K_S / M_S
    a[1, 3] = C_S / M_S
    a[3, 0] = K_S / M_H
    a[3, 1] = C_S / M_H
    a[3, 2] = -(K_S + K_H) / M_H
    a[3, 3] = -(C_S + C_H) / M_H
    a[3, 4] = K_H / M_H
    a[3, 5] = C_H / M_H
    a[5, 2] = K_H / M_T
    a[5, 3] = C_H / M_T
    a[5, 4] = -(K_H + K_T) / M_T
    a[5, 5] = -C_H / M_T
    b = np.zeros(6)
    b[3] = -G / M_H
    b[5] = G / M_T
    e = np.zeros(6)
    e[5] = K_T / M_T
    return a, b, e


A, B, E = plant()


def road(t):
    return AMPLITUDE * np.sin(OMEGA * t)


def sample_times(duration):
    n = int(round(duration / SAMPLE))
    return np.arange(n + 1) * SAMPLE


def rms_values(t, x):
    """RMS of BA, SDD, TDD over the samples after the start."""
    t, x = t[1:], x[1:]
    with np.errstate(all="ignore"):  # a diverged peer gives inf, not a warning
        ba = x @ A[1]
        sdd = x[:, 0] - x[:, 4]
        tdd = x[:, 4] - road(t)
        return np.sqrt(np.mean(np.stack([ba, sdd, tdd]) ** 2, axis=1))


def errors(x, rms, ref):
    """State error (relative max norm) and RMS errors against `ref`."""
    n = min(len(x), len(ref["x"]))
    scale = np.abs(ref["x"][:n]).max(axis=0)
    with np.errstate(all="ignore"):
        state = float((np.abs(x[:n] - ref["x"][:n]) / scale).max())
        rms_err = np.abs(rms - ref["rms"]) / ref["rms"]
    return state, [float(v) for v in rms_err]


# ---------------------------------------------------------------- tdvass


def tdvass_binary(path):
    if path:
        return Path(path)
    target = os.environ.get("CARGO_TARGET_DIR")
    target_dir = Path(target) if target else ROOT / "target"
    if not target_dir.is_absolute():
        target_dir = ROOT / target_dir
    binary = target_dir / "release" / "tdvass"
    if not binary.is_file():
        subprocess.run(
            ["cargo", "build", "--release", "--bin", "tdvass"], cwd=ROOT, check=True
        )
    return binary


def tdvass_trajectory(binary, duration, max_step=None):
    """The CLI's trajectory at the default tolerance, or with its internal
    step capped at `max_step` (s)."""
    cap = [] if max_step is None else ["--max-internal-step", repr(max_step)]
    with tempfile.TemporaryDirectory() as d:
        csv = Path(d) / "run.csv"
        subprocess.run(
            [
                str(binary), "simulate", "--duration", str(duration), *cap,
                "--output", str(csv), "--output-interval", repr(SAMPLE),
            ],
            check=True, stdout=subprocess.DEVNULL,
        )
        data = np.loadtxt(csv, delimiter=",", skiprows=1)
    t, x = data[:, 0], data[:, 1:7]
    return {"t": t, "x": x, "rms": rms_values(t, x)}


def tdvass_timing(binary, duration, repeats):
    """Wall time of `tdvass simulate --json` (process start included)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run(
            [str(binary), "simulate", "--duration", str(duration), "--json"],
            check=True, stdout=subprocess.DEVNULL,
        )
        times.append(time.perf_counter() - start)
    return statistics.median(times)


# ------------------------------------------------------------ scipy RK45


def scipy_method_of_steps(duration, rtol, atol, method="RK45"):
    """Explicit Runge-Kutta stepped by hand, each step at most tau long, so
    that every delayed argument t - tau of a stage falls in an earlier,
    completed step, whose dense output gives x_t there."""
    from scipy.integrate import DOP853, RK45

    cls = {"RK45": RK45, "DOP853": DOP853}[method]
    history = []  # (t_start, t_end, dense output), in order

    def delayed_tire(s):
        if s <= 0.0:
            return 0.0
        for i in range(len(history) - 1, -1, -1):
            t0, t1, dense = history[i]
            if s >= t0:
                return dense(s)[4]
        return 0.0

    def rhs(t, x):
        return A @ x + B * delayed_tire(t - TAU) + E * road(t)

    solver = cls(rhs, 0.0, np.zeros(6), duration, rtol=rtol, atol=atol, max_step=TAU)
    ts = sample_times(duration)
    out = np.zeros((len(ts), 6))
    next_sample = 1
    while solver.status == "running":
        t_old = solver.t
        solver.step()
        dense = solver.dense_output()
        history.append((t_old, solver.t, dense))
        if len(history) > 64:
            del history[:32]
        while next_sample < len(ts) and ts[next_sample] <= solver.t + 1e-12:
            out[next_sample] = dense(ts[next_sample])
            next_sample += 1
    if solver.status != "finished":
        raise RuntimeError(solver.message)
    return {"t": ts, "x": out, "rms": rms_values(ts, out), "steps": solver.nfev}


# ---------------------------------------------------------------- ddeint


def ddeint_run(duration, grid):
    from ddeint import ddeint

    def model(y, t):
        return A @ y(t) + B * y(t - TAU)[4] + E * road(t)

    n = int(round(duration / grid))
    tt = np.arange(n + 1) * grid
    x = ddeint(model, lambda t: np.zeros(6), tt)
    every = int(round(SAMPLE / grid))
    ts, xs = tt[::every], x[::every]
    return {"t": ts, "x": xs, "rms": rms_values(ts, xs)}


# --------------------------------------------------------------- JiTCDDE


def jitcdde_build(rtol, atol):
    import symengine
    from jitcdde import jitcdde, t, y

    rhs = []
    for i in range(6):
        expr = sum(A[i, j] * y(j) for j in range(6) if A[i, j] != 0.0)
        if B[i] != 0.0:
            expr += B[i] * y(4, t - TAU)
        if E[i] != 0.0:
            expr += E[i] * AMPLITUDE * symengine.sin(OMEGA * t)
        rhs.append(expr)
    dde = jitcdde(rhs, verbose=False)
    dde.constant_past(np.zeros(6), time=0.0)
    dde.set_integration_parameters(rtol=rtol, atol=atol)
    return dde


def jitcdde_run(dde, duration):
    ts = sample_times(duration)
    out = np.zeros((len(ts), 6))
    with warnings.catch_warnings():
        # JiTCDDE warns when a sampling point lies inside its last step.
        warnings.simplefilter("ignore")
        dde.adjust_diff()
        for i, ti in enumerate(ts[1:], start=1):
            out[i] = dde.integrate(ti)
    return {"t": ts, "x": out, "rms": rms_values(ts, out)}


# ------------------------------------------------------------------ main


def machine():
    cpu = "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import scipy

    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "load_average": os.getloadavg(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "platform": platform.platform(),
    }


def timed(fn, repeats):
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return result, statistics.median(times), times


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--smoke", action="store_true", help="0.5 s, one repetition (CI)")
    parser.add_argument("--tdvass", help="path of the tdvass binary")
    parser.add_argument("--duration", type=float, help="simulated time (s)")
    parser.add_argument("--repeats", type=int, help="timing repetitions")
    parser.add_argument("--skip", default="", help="comma-separated peers to leave out")
    parser.add_argument("--json", help="write the results here")
    args = parser.parse_args()
    duration = args.duration or (0.5 if args.smoke else 15.0)
    repeats = args.repeats or (1 if args.smoke else 3)
    skip = set(filter(None, args.skip.split(",")))
    binary = tdvass_binary(args.tdvass)

    info = machine()
    print(f"machine: {info['cpu']}, {info['cores']} cores, load {info['load_average']}")
    print(f"python {info['python']}, numpy {info['numpy']}, scipy {info['scipy']}")
    print(f"case: TDVASS g = {G}, tau = {TAU}, x_g = {AMPLITUDE} sin {OMEGA}t, "
          f"{duration} s from rest; errors on a {SAMPLE * 1e3:g} ms grid")

    ref = tdvass_trajectory(binary, duration, REFERENCE_STEP)
    results = []

    def report(name, run, seconds, note=""):
        state, rms_err = errors(run["x"], run["rms"], ref)
        row = {
            "solver": name, "seconds": seconds, "state_error": state,
            "rms_error": rms_err, "rms": [float(v) for v in run["rms"]], "note": note,
        }
        results.append(row)
        print(f"  {name:34s} {seconds * 1e3:10.1f} ms   state err {state:8.1e}   "
              f"RMS err {max(rms_err):8.1e}  {note}", flush=True)
        return row

    print("solver                                   wall time   accuracy vs reference")
    run = tdvass_trajectory(binary, duration)
    seconds = tdvass_timing(binary, duration, max(repeats, 5))
    base = report("tdvass CLI (tolerance 1e-6)", run, seconds, "process start included")

    tight = None
    if "scipy" not in skip:
        for rtol in [1e-6, 1e-12]:
            run, seconds, _ = timed(
                lambda rtol=rtol: scipy_method_of_steps(duration, rtol, rtol * 1e-3), repeats
            )
            report(f"scipy RK45 steps<=tau rtol {rtol:g}", run, seconds,
                   f"{run['steps']} RHS calls")
            tight = run
        # Independent check of the reference: tdvass at a tiny step against
        # scipy at its tightest tolerance.
        check = float(np.abs(tight["x"] - ref["x"]).max() / np.abs(ref["x"]).max())
        print(f"  reference check: |tdvass(h=2e-6) - scipy(rtol 1e-12)| = {check:.1e} (relative)")
        if check > 1e-6:
            sys.exit(f"the reference and scipy disagree by {check:.1e}")

    if "ddeint" not in skip:
        try:
            import ddeint  # noqa: F401

            for grid in [1e-3] if args.smoke else [1e-3, 2e-4]:
                if not args.smoke and grid < 1e-3 and duration > 3.0:
                    # O(n^2) history rebuild: measure 3 s and scale by the
                    # measured growth (reported as an estimate).
                    part = 3.0
                    run, seconds, _ = timed(lambda: ddeint_run(part, grid), 1)
                    half, seconds_half, _ = timed(lambda: ddeint_run(part / 2, grid), 1)
                    growth = np.log2(seconds / seconds_half)
                    estimate = seconds * (duration / part) ** growth
                    sub_ref = {"x": ref["x"][: len(run["x"])],
                               "rms": rms_values(ref["t"][: len(run["x"])], ref["x"][: len(run["x"])])}
                    state, rms_err = errors(run["x"], run["rms"], sub_ref)
                    row = {"solver": f"ddeint grid {grid:g}", "seconds": estimate,
                           "state_error": state, "rms_error": rms_err,
                           "note": f"estimated from {part:g} s (time ~ T^{growth:.2f})"}
                    results.append(row)
                    print(f"  {row['solver']:34s} {estimate * 1e3:10.1f} ms   state err {state:8.1e}   "
                          f"RMS err {max(rms_err):8.1e}  {row['note']}", flush=True)
                    continue
                run, seconds, _ = timed(lambda grid=grid: ddeint_run(duration, grid), 1)
                report(f"ddeint grid {grid:g}", run, seconds, "one run")
        except ImportError:
            print("  ddeint: not installed")

    if "jitcdde" not in skip:
        try:
            import jitcdde  # noqa: F401

            for rtol in [1e-6, 1e-10]:
                start = time.perf_counter()
                dde = jitcdde_build(rtol, rtol * 1e-3)
                dde.compile_C(simplify=False)
                compile_seconds = time.perf_counter() - start
                run, seconds, _ = timed(lambda: jitcdde_run(dde, duration), 1)
                report(f"JiTCDDE rtol {rtol:g}", run, seconds,
                       f"+ {compile_seconds:.1f} s to generate and compile C")
        except ImportError:
            print("  JiTCDDE: not installed")
        except Exception as error:  # a C compiler problem, say
            print(f"  JiTCDDE: failed ({type(error).__name__}: {error})")

    print("ratios (peer wall time / tdvass CLI wall time):")
    for row in results[1:]:
        print(f"  {row['solver']:34s} {row['seconds'] / base['seconds']:10.0f}x   "
              f"state err {row['state_error']:8.1e} (tdvass {base['state_error']:.1e})")
    # Only tdvass is held to an accuracy here (the peers' errors are data).
    if not base["state_error"] < 1e-6:
        sys.exit(f"tdvass: state error {base['state_error']:.1e} against the reference")
    if args.json:
        Path(args.json).write_text(json.dumps(
            {"machine": info, "duration": duration, "results": results}, indent=2))


if __name__ == "__main__":
    main()
