"""Monte Carlo over road seeds (or a (g, tau) grid) of the FMU with fmpy on dask.distributed.

Every task runs the FMU with fmpy on a dask worker and returns the RMS values
and J of Eq. (6), and the field metrics (ISO 2631-1 W_k-weighted a_w,
vibration dose value, RMS dynamic tire load / static load, contact loss time,
max |SDD|); the client gathers them into one CSV and a plot.

- `--mode seeds` (default): road seeds 1..N x CS / PVASS / TDVASS on a random
  road (`--road iso8608` = FMU road 2, the correct ISO 8608 road, default;
  `--road paper` = road 3, the paper-compatible road), TDVASS at
  (g2, tau2) = (2528 N/m, 1.28e-4 s). The plot shows the distribution of each
  RMS value and how the Monte Carlo mean converges with the number of seeds.
- `--mode grid`: TDVASS over a (g, tau) grid on the harmonic road (or `--road`),
  J and the spectral abscissa per point: the landscape the PSO searches.

Where it runs: a `LocalCluster` with `--workers 2` processes by default, or an
existing cluster with `--scheduler tcp://HOST:8786` (start `dask scheduler` on
one machine and `dask worker tcp://HOST:8786` on each of the others; see
examples/README.md). The FMU file is sent to the workers through the
scheduler (no shared file system needed); each worker process needs Python
with fmpy and numpy and a linux64 platform.

    python examples/sweep_dask.py [--quick] [--out out] [--scheduler tcp://host:8786]
           [--workers 2] [--mode seeds|grid] [--seeds 200] [--road iso8608|paper]

Writes sweep_dask.csv, sweep_dask.png and sweep_dask.txt.
"""

from __future__ import annotations

import hashlib
import logging
import time
from pathlib import Path

import numpy as np

import _common as C

ROAD_CODES = {"harmonic": 1, "iso8608": 2, "paper": 3}
ROAD_NAMES = {1: "harmonic road 0.05 sin 5t", 2: "ISO 8608 class C road, 20 m/s",
              3: "paper-compatible class C road, 20 m/s"}
FIELDS = ["road", "road_seed", "variant", "g", "tau", "rms_body_acceleration", "rms_suspension_deflection",
          "rms_tire_deflection_mm", "objective", *C.FIELD_OUTPUTS, "spectral_abscissa", "error", "worker",
          "seconds"]


# ---------------------------------------------------------------------------
# Worker side. This function is shipped to the workers by value (cloudpickle),
# so it only uses fmpy, numpy and the standard library, never `_common`.
# ---------------------------------------------------------------------------
def run_batch(fmu_bytes: bytes, digest: str, duration: float, jobs: list[dict]) -> list[dict]:
    """Runs every job (a dict of FMU start values) for `duration` s; one row per job."""
    import os
    import tempfile
    import threading
    import time as _time

    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    try:
        from distributed import get_worker

        worker = get_worker()
        where = worker.address
    except Exception:  # called outside a worker (e.g. a test)
        worker, where = run_batch, "local"

    # one extracted FMU + slave per (worker process, thread, FMU digest), reused across tasks
    cache = worker.__dict__.setdefault("_tdvass_fmu_cache", {})
    key = (digest, threading.get_ident())
    if key not in cache:
        path = os.path.join(tempfile.gettempdir(), f"tdvass-{digest[:16]}.fmu")
        if not os.path.exists(path):
            tmp = f"{path}.{os.getpid()}.{threading.get_ident()}"
            with open(tmp, "wb") as fh:
                fh.write(fmu_bytes)
            os.replace(tmp, path)
        md = read_model_description(path)
        cache[key] = {"md": md, "dir": extract(path), "slave": None, "path": path,
                      "vars": {v.name: v for v in md.modelVariables}}
    entry = cache[key]
    md, variables = entry["md"], entry["vars"]
    outputs = ["rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection", "objective",
               "rms_weighted_body_acceleration", "vibration_dose_value", "rms_dynamic_tire_load_ratio",
               "contact_loss_time", "max_suspension_deflection"]
    out_vrs = [variables[n].valueReference for n in outputs]

    rows = []
    for job in jobs:
        t0 = _time.perf_counter()
        slave = entry["slave"]
        if slave is not None:
            try:
                slave.reset()
            except Exception:
                slave = entry["slave"] = None
        if slave is None:
            slave = FMU2Slave(guid=md.guid, unzipDirectory=entry["dir"],
                              modelIdentifier=md.coSimulation.modelIdentifier, instanceName="sweep")
            slave.instantiate()
            entry["slave"] = slave
        for name, value in job.items():
            v = variables[name]
            if v.type == "Real":
                slave.setReal([v.valueReference], [float(value)])
            else:
                slave.setInteger([v.valueReference], [int(value)])
        slave.setupExperiment(startTime=0.0, stopTime=duration)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        sa = slave.getReal([variables["spectral_abscissa"].valueReference])[0]
        error = ""
        try:
            # the RMS outputs are accumulated on the internal grid: one communication step will do
            slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=duration)
            values = slave.getReal(out_vrs)
        except Exception as exc:  # diverged (fmi2Discard) or failed
            error = (str(exc) or type(exc).__name__).replace(",", ";").replace("\n", " ")
            values = [float("nan")] * len(outputs)
        try:
            slave.terminate()
        except Exception:
            try:
                slave.freeInstance()
            except Exception:
                pass
            entry["slave"] = None
        row = dict(job)
        row.update(zip(outputs[4:], values[4:]))
        row.update({"rms_body_acceleration": values[0], "rms_suspension_deflection": values[1],
                    "rms_tire_deflection_mm": 1e3 * values[2], "objective": values[3],
                    "spectral_abscissa": sa, "error": error, "worker": where,
                    "seconds": _time.perf_counter() - t0})
        rows.append(row)
    return rows


def cleanup_worker(dask_worker=None) -> int:
    """Frees the cached FMU instances of a worker process and removes their files
    (`client.run` passes the worker as `dask_worker`)."""
    import os
    import shutil

    worker = dask_worker if dask_worker is not None else run_batch
    cache = worker.__dict__.pop("_tdvass_fmu_cache", {})
    for entry in cache.values():
        if entry["slave"] is not None:
            try:
                entry["slave"].freeInstance()
            except Exception:
                pass
        shutil.rmtree(entry["dir"], ignore_errors=True)
        try:
            os.remove(entry["path"])
        except OSError:
            pass
    return len(cache)


# ---------------------------------------------------------------------------
# Client side
# ---------------------------------------------------------------------------
def make_client(args):
    from distributed import Client, LocalCluster

    if args.scheduler:
        client = Client(args.scheduler)
        return client, None
    cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                           dashboard_address=None, silence_logs=logging.ERROR)
    return Client(cluster), cluster


def seed_tasks(args, nseeds):
    road = ROAD_CODES[args.road]
    for seed in range(1, nseeds + 1):
        jobs = []
        for v, code in C.VARIANTS.items():
            jobs.append({"variant": code, "road": road, "road_seed": seed, "g": C.G2, "tau": C.TAU2})
        yield jobs


def grid_tasks(args, ng, nt):
    road = ROAD_CODES[args.road]
    gains = np.linspace(args.g_min, args.g_max, ng)
    delays = np.linspace(0.0, args.tau_max, nt)
    for g in gains:  # one task per gain: nt runs
        yield [{"variant": 3, "road": road, "road_seed": 1, "g": float(g), "tau": float(tau)} for tau in delays]


def plot_seeds(rows, args, nworkers, elapsed, out):
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(14, 8.5), constrained_layout=True)
    keys = ["rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection_mm"]
    road = ROAD_CODES[args.road]
    nseeds = max(r["road_seed"] for r in rows)
    from matplotlib.ticker import MaxNLocator

    ordered = sorted(rows, key=lambda r: r["road_seed"])
    for k, (key, metric) in enumerate(zip(keys, C.METRICS)):
        ax = axes[0, k]
        allv = np.array([r[key] for r in rows])
        edges = np.histogram_bin_edges(allv[np.isfinite(allv)], bins=max(10, min(60, nseeds // 2)))
        for v, code in C.VARIANTS.items():
            vals = np.array([r[key] for r in ordered if r["variant"] == code])
            ax.hist(vals, bins=edges, alpha=0.55, color=C.COLORS[v],
                    edgecolor="k", lw=0.5, label=f"{C.LABELS[v]}: {vals.mean():.4g} ± {vals.std(ddof=1):.2g}")
            if road == 3:
                ax.axvline(C.TABLE3[v][k], color=C.COLORS[v], ls="--", lw=1.5)
            ax2 = axes[1, k]
            n = np.arange(1, vals.size + 1)
            mean = np.cumsum(vals) / n
            sq = np.cumsum(vals ** 2) / n
            sd = np.sqrt(np.maximum(sq - mean ** 2, 0) * n / np.maximum(n - 1, 1))
            ci = 1.96 * sd / np.sqrt(n)
            ax2.plot(n, mean, color=C.COLORS[v], lw=1.5, label=C.LABELS[v])
            ax2.fill_between(n, mean - ci, mean + ci, color=C.COLORS[v], alpha=0.2)
        ax.set_xlabel(f"RMS {metric}")
        ax.set_ylabel("number of seeds")
        ax.set_title(f"distribution over {nseeds} road seeds"
                     + (" (dashed: paper Table 3)" if road == 3 else ""), fontsize=10)
        ax.legend(fontsize=8.5)
        ax.grid(True, alpha=0.3)
        ax.xaxis.set_major_locator(MaxNLocator(6))
        ax2 = axes[1, k]
        ax2.set_xlabel("number of road seeds")
        ax2.set_ylabel(f"running mean of RMS {metric}")
        ax2.set_title("Monte Carlo mean with 95 % confidence band", fontsize=10)
        ax2.grid(True, alpha=0.3)
        ax2.legend(fontsize=8.5)
    fig.suptitle(f"Monte Carlo over road seeds on dask.distributed ({nworkers} workers, {elapsed:.1f} s): "
                 f"{ROAD_NAMES[road]}, 15 s from rest; TDVASS g2 = {C.G2:g} N/m, τ2 = {C.TAU2:g} s")
    C.save_figure(fig, out, "sweep_dask")


def plot_grid(rows, args, nworkers, elapsed, out):
    import matplotlib.pyplot as plt

    gains = np.unique([r["g"] for r in rows])
    delays = np.unique([r["tau"] for r in rows])
    J = np.full((delays.size, gains.size), np.nan)
    S = np.full_like(J, np.nan)
    for r in rows:
        i, j = np.searchsorted(delays, r["tau"]), np.searchsorted(gains, r["g"])
        S[i, j] = r["spectral_abscissa"]
        if not r["error"] and r["spectral_abscissa"] < 0:
            J[i, j] = r["objective"]
    from matplotlib.colors import LogNorm

    fig, ax = plt.subplots(figsize=(10, 7), layout="constrained")
    norm = LogNorm() if np.nanmin(J) > 0 else None
    mesh = ax.pcolormesh(gains, delays * 1e3, J, shading="nearest", cmap="viridis", norm=norm)
    fig.colorbar(mesh, ax=ax, label="objective J (Eq. 6, log scale); grey: unstable")
    if np.isfinite(S).any() and (S >= 0).any() and (S < 0).any():
        ax.contour(gains, delays * 1e3, S, levels=[0.0], colors="w", linewidths=1.5)
        ax.plot([], [], "w-", label="stability boundary (spectral abscissa = 0)")
    if np.isfinite(J).any():
        i, j = np.unravel_index(np.nanargmin(J), J.shape)
        ax.plot(gains[j], delays[i] * 1e3, "r*", ms=16, mec="k",
                label=f"smallest J = {J[i, j]:.4f} at g = {gains[j]:.0f} N/m, τ = {delays[i] * 1e3:.2f} ms")
    ax.plot(C.G1, C.TAU1 * 1e3, "wo", mec="k", ms=9, label=f"paper (g1, τ1) = ({C.G1:g}, {C.TAU1:g})")
    ax.set_xlabel("feedback gain g (N/m)")
    ax.set_ylabel("delay τ (ms)")
    ax.set_facecolor("0.85")
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncol=2, fontsize=9,
               facecolor="0.85")
    road = ROAD_CODES[args.road]
    ax.set_title(f"J over (g, τ) on dask.distributed ({nworkers} workers, {elapsed:.1f} s): TDVASS, "
                 f"{ROAD_NAMES[road]}, 15 s from rest", fontsize=10.5)
    C.save_figure(fig, out, "sweep_dask")


def main() -> None:
    p = C.parser(__doc__.splitlines()[0])
    p.add_argument("--fmu", default=None, help="FMU path (default $TDVASS_FMU or target/fmu/tdvass.fmu)")
    p.add_argument("--scheduler", default=None, help="address of a running dask scheduler, e.g. tcp://host:8786 "
                                                     "(default: start a LocalCluster)")
    p.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    p.add_argument("--mode", choices=["seeds", "grid"], default="seeds",
                   help="seeds: Monte Carlo over road seeds x variants; grid: TDVASS over (g, tau)")
    p.add_argument("--road", choices=list(ROAD_CODES), default=None,
                   help="default iso8608 (seeds) or harmonic (grid)")
    p.add_argument("--seeds", type=int, default=None, help="seeds mode: road seeds 1..N; default 200 (6 with --quick)")
    p.add_argument("--g-min", type=float, default=0.0, help="grid mode (N/m)")
    p.add_argument("--g-max", type=float, default=20000.0, help="grid mode (N/m)")
    p.add_argument("--tau-max", type=float, default=0.05, help="grid mode (s)")
    p.add_argument("--grid", type=int, nargs=2, default=None, metavar=("NG", "NTAU"),
                   help="grid mode size; default 41 26 (5 4 with --quick)")
    p.add_argument("--duration", type=float, default=15.0, help="simulated time per run (s)")
    args = p.parse_args()
    out = C.prepare_out(args.out)
    if args.road is None:
        args.road = "iso8608" if args.mode == "seeds" else "harmonic"

    fmu_file = Path(args.fmu or C.fmu_path())
    data = fmu_file.read_bytes()
    digest = hashlib.sha256(data).hexdigest()

    if args.mode == "seeds":
        nseeds = args.seeds or (6 if args.quick else 200)
        batches = list(seed_tasks(args, nseeds))
    else:
        ng, nt = args.grid or ((5, 4) if args.quick else (41, 26))
        batches = list(grid_tasks(args, ng, nt))

    client, cluster = make_client(args)
    try:
        nworkers = len(client.scheduler_info()["workers"])
        print(f"dask: {client.scheduler.address}, {nworkers} workers; {sum(map(len, batches))} runs "
              f"in {len(batches)} tasks")
        t0 = time.perf_counter()
        fmu_future = client.scatter(data, broadcast=True)  # the FMU travels with the tasks
        futures = [client.submit(run_batch, fmu_future, digest, args.duration, jobs, pure=False)
                   for jobs in batches]
        rows = [row for batch in client.gather(futures) for row in batch]
        elapsed = time.perf_counter() - t0
        client.run(cleanup_worker)  # free the FMU instances, remove the unpacked FMUs
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

    with open(out / "sweep_dask.csv", "w") as fh:
        fh.write(",".join(FIELDS) + "\n")
        for r in rows:
            fh.write(",".join(str(r.get(f, "")) for f in FIELDS) + "\n")

    per_worker = {}
    for r in rows:
        per_worker[r["worker"]] = per_worker.get(r["worker"], 0) + 1
    errors = sum(1 for r in rows if r["error"])
    lines = [f"sweep_dask ({args.mode}): {len(rows)} FMU runs in {len(batches)} dask tasks on {nworkers} workers, "
             f"{elapsed:.2f} s wall clock, {sum(r['seconds'] for r in rows):.2f} s of FMU time",
             "runs per worker: " + ", ".join(f"{w}: {n}" for w, n in sorted(per_worker.items())),
             f"runs that failed or diverged: {errors}", ""]
    if args.mode == "seeds":
        road = ROAD_CODES[args.road]
        lines.append(f"{ROAD_NAMES[road]}, seeds 1..{nseeds}, RMS mean +- sd (paper Table 3 in brackets, "
                     f"comparable on the paper-compatible road only):")
        keys = ["rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection_mm"]
        for v, code in C.VARIANTS.items():
            line = f"  {C.LABELS[v]:<7}"
            for k, key in enumerate(keys):
                vals = np.array([r[key] for r in rows if r["variant"] == code])
                line += f"  {C.METRICS_ASCII[k]} {vals.mean():.4f} +- {vals.std(ddof=1):.4f} [{C.TABLE3[v][k]}]"
            lines.append(line)
        lines.append("field metrics, mean +- sd (comfort: ISO 2631-1 at the mean a_w):")
        for v, code in C.VARIANTS.items():
            vals = np.array([[r[key] for key in C.FIELD_OUTPUTS] for r in rows if r["variant"] == code])
            m, sd = vals.mean(axis=0), vals.std(axis=0, ddof=1)
            lines.append(f"  {C.LABELS[v]:<7}" + "".join(f"  {h} {a:.4f} +- {b:.4f}"
                                                          for h, a, b in zip(C.FIELD_METRICS.values(), m, sd))
                         + f"  ({C.comfort_reaction(m[0])})")
        counts = []
        for v, code in C.VARIANTS.items():
            runs = [r for r in rows if r["variant"] == code]
            over = sum(r["rms_dynamic_tire_load_ratio"] > C.TIRE_LOAD_RATIO_LIMIT for r in runs)
            lost = sum(r["contact_loss_time"] > 0 for r in runs)
            counts.append(f"{C.LABELS[v]} {over} / {lost}")
        lines.append("runs with RMS tire load ratio > 1/3 / with contact loss: " + ", ".join(counts))
        plot_seeds(rows, args, nworkers, elapsed, out)
    else:
        good = [r for r in rows if not r["error"] and r["spectral_abscissa"] < 0]
        best = min(good, key=lambda r: r["objective"]) if good else None
        lines.append(f"TDVASS on the {ROAD_NAMES[ROAD_CODES[args.road]]}, g in [{args.g_min:g}, {args.g_max:g}] N/m, "
                     f"tau in [0, {args.tau_max:g}] s: {len(good)} of {len(rows)} points stable")
        if best:
            lines.append(f"smallest J = {best['objective']:.6f} at g = {best['g']:.0f} N/m, tau = {best['tau']:.4g} s")
            calm = min(good, key=lambda r: r["rms_weighted_body_acceleration"])
            lines.append(f"smallest a_w = {calm['rms_weighted_body_acceleration']:.4f} m/s^2 "
                         f"({C.comfort_reaction(calm['rms_weighted_body_acceleration'])}) at g = {calm['g']:.0f} N/m, "
                         f"tau = {calm['tau']:.4g} s (tire load ratio {calm['rms_dynamic_tire_load_ratio']:.3f}, "
                         f"max |SDD| {calm['max_suspension_deflection']:.4f} m)")
        plot_grid(rows, args, nworkers, elapsed, out)
    C.write_summary(out, "sweep_dask", "\n".join(lines))


if __name__ == "__main__":
    main()
