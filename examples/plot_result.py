"""Plot a tdvass run with matplotlib: an fmpy result or a `tdvass simulate --output` CSV.

fmpy's own ``fmpy.util.plot_result`` draws with plotly and exports pictures
through a Chrome build (kaleido), which a plain ``pip install fmpy`` does not
provide. This helper needs only matplotlib and numpy.

As a script (writes ``<out>/plot_result.png`` and ``<out>/plot_result.txt``,
the range and RMS of each plotted output):

    python examples/plot_result.py                       # the FMU's default experiment
    python examples/plot_result.py --start variant=1 --start road=2 --stop 10
    python examples/plot_result.py --csv out.csv         # from `tdvass simulate --output out.csv`
    python examples/plot_result.py --names body_acceleration tire_deflection

As a library (``examples/`` on ``sys.path``):

    from plot_result import plot_result
    plot_result(result, names=["body_acceleration"], filename="ba.png")

where ``result`` is what ``fmpy.simulate_fmu`` returns (a structured array
with a ``time`` field) or a dict of arrays with a ``time`` key.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

# What is plotted when no names are given, with the unit of each output.
DEFAULT_NAMES = ("body_acceleration", "suspension_deflection", "tire_deflection", "road_displacement")
UNITS = {
    "x_s": "m", "v_s": "m/s", "x_h": "m", "v_h": "m/s", "x_t": "m", "v_t": "m/s",
    "body_acceleration": "m/s²", "suspension_deflection": "m", "tire_deflection": "m",
    "road_displacement": "m", "control_force": "N",
    "rms_body_acceleration": "m/s²", "rms_suspension_deflection": "m", "rms_tire_deflection": "m",
    "objective": "–",
}


def _columns(result) -> dict[str, np.ndarray]:
    """A dict of arrays from an fmpy structured array or a dict."""
    if isinstance(result, dict):
        return {name: np.asarray(values) for name, values in result.items()}
    return {name: np.asarray(result[name]) for name in result.dtype.names}


def plot_result(result, names=None, filename: str | Path = "plot_result.png", title: str | None = None) -> Path:
    """Plots each of ``names`` against time, one panel each; returns the PNG path.

    Without ``names``: those of BA, SDD, TDD and the road that the result has, or else every column.
    """
    import matplotlib.pyplot as plt

    columns = _columns(result)
    if "time" not in columns:
        raise ValueError("the result has no `time` column")
    if not names:
        names = [n for n in DEFAULT_NAMES if n in columns] or [n for n in columns if n != "time"]
    names = [n for n in names if n != "time"]
    unknown = [n for n in names if n not in columns]
    if unknown:
        raise KeyError(f"not in the result: {', '.join(unknown)}; available: {', '.join(sorted(columns))}")
    fig, axes = plt.subplots(len(names), 1, sharex=True, figsize=(9, 2.2 * len(names) + 0.8),
                             constrained_layout=True, squeeze=False)
    time = columns["time"]
    for ax, name in zip(axes[:, 0], names):
        ax.plot(time, columns[name], lw=1.0)
        ax.set_ylabel(f"{name}\n({UNITS.get(name, '?')})", fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("time (s)")
    if title:
        fig.suptitle(title)
    path = Path(filename)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _start_value(text: str):
    """NAME=VALUE with VALUE an int or a float."""
    name, _, value = text.partition("=")
    if not name or not value:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got {text!r}")
    try:
        return name, int(value)
    except ValueError:
        return name, float(value)


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--csv", type=Path, help="plot this CSV (from `tdvass simulate --output`) instead of running the FMU")
    p.add_argument("--fmu", help="the FMU (default: $TDVASS_FMU, else <target>/fmu/tdvass.fmu)")
    p.add_argument("--start", action="append", type=_start_value, default=[], metavar="NAME=VALUE",
                   help="a start value of the FMU (repeatable), e.g. variant=1")
    p.add_argument("--stop", type=float, default=None, help="stop time of the FMU run (s; default: the FMU's 15 s)")
    p.add_argument("--names", nargs="+", default=None, help=f"what to plot (default: {' '.join(DEFAULT_NAMES)})")
    p.add_argument("--out", type=Path, default=Path("out"), help="output directory (default: out)")
    p.add_argument("--quick", action="store_true", help="a 2 s FMU run (used by the tests)")
    args = p.parse_args(argv)

    if args.csv:
        data = np.genfromtxt(args.csv, delimiter=",", names=True)
        result, title = data, f"{args.csv}"
    else:
        from fmpy import simulate_fmu

        import _common as C

        fmu = args.fmu or C.fmu_path()
        stop = 2.0 if args.quick and args.stop is None else args.stop
        names = list(args.names or DEFAULT_NAMES)
        # An explicit output interval: fmpy's default can be coarser than the FMU's 1 ms step.
        result = simulate_fmu(fmu, start_values=dict(args.start), stop_time=stop, output_interval=1e-3,
                              output=names)
        title = "tdvass FMU" + (", " + ", ".join(f"{k} = {v}" for k, v in args.start) if args.start else "")
    path = plot_result(result, args.names, args.out / "plot_result.png", title)
    print(f"wrote {path}")
    columns = _columns(result)
    lines = [f"{title}, t = {columns['time'][0]:g} .. {columns['time'][-1]:g} s, {columns['time'].size} points",
             f"{'output':<28}{'unit':>6}{'min':>14}{'max':>14}{'RMS':>14}"]
    for name in args.names or [n for n in DEFAULT_NAMES if n in columns]:
        y = columns[name]
        lines.append(f"{name:<28}{UNITS.get(name, '?'):>6}{y.min():>14.6g}{y.max():>14.6g}"
                     f"{np.sqrt(np.mean(y ** 2)):>14.6g}")
    summary = args.out / "plot_result.txt"
    summary.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines))
    print(f"wrote {summary}")


if __name__ == "__main__":
    main()
