"""CS, PVASS and TDVASS on the harmonic road x_g = 0.05 sin 5t (paper Table 2, Fig. 11).

Runs the FMU with fmpy three times (variant = 1, 2, 3; road = 1, harmonic;
TDVASS with g1 = 5386 N/m, tau1 = 2e-4 s), 15 s from rest, and reads the
RMS values of BA, SDD and TDD from the FMU's running-RMS outputs at the end
(RMS over the whole 0-15 s, transient included, as the paper did; notes
section 3). Beside the paper's columns it reads the field metrics of the
FMU: the ISO 2631-1 W_k-weighted RMS body acceleration a_w (with the
standard's comfort reaction), the vibration dose value, the RMS dynamic tire
load over the static load, the time without tire contact and max |SDD|.
Writes table2.png (time histories like Fig. 11, the RMS table next to the
paper's and the field metrics), table2.csv (the time histories, with the
weighted body acceleration and the dynamic tire load) and table2.txt.

    python examples/table2.py [--quick] [--out out] [--fmu path/to/tdvass.fmu]
"""

from __future__ import annotations

import _common as C

OUTPUTS = ["body_acceleration", "suspension_deflection", "tire_deflection", "road_displacement",
           "x_s", "control_force",
           "rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection", "objective",
           "weighted_body_acceleration", "dynamic_tire_load", *C.FIELD_OUTPUTS]


def main() -> None:
    p = C.parser(__doc__.splitlines()[0])
    p.add_argument("--fmu", default=None, help="FMU path (default $TDVASS_FMU or target/fmu/tdvass.fmu)")
    p.add_argument("--duration", type=float, default=15.0, help="simulated time (s)")
    p.add_argument("--step", type=float, default=None,
                   help="communication step (s); default 0.002 (0.01 with --quick)")
    args = p.parse_args()
    out = C.prepare_out(args.out)
    step = args.step or (0.01 if args.quick else 0.002)

    results = {}
    with C.FmuRunner(args.fmu) as fmu:
        for v, code in C.VARIANTS.items():
            params = {"variant": code, "road": 1, "road_amplitude": 0.05, "road_angular_frequency": 5.0,
                      "g": C.G1, "tau": C.TAU1}
            r = fmu.run(params, args.duration, step, OUTPUTS)
            if r["error"]:
                raise SystemExit(f"{v}: {r['error']}")
            results[v] = r

    t = results["cs"]["time"]
    with open(out / "table2.csv", "w") as fh:
        cols = ["body_acceleration", "suspension_deflection", "tire_deflection"]
        extra = ["weighted_body_acceleration", "dynamic_tire_load"]
        fh.write("time," + ",".join(f"{v}_{c}" for v in C.VARIANTS for c in cols) + ",road_displacement,"
                 + ",".join(f"{v}_{c}" for v in C.VARIANTS for c in extra) + "\n")
        for i in range(t.size):
            fh.write(f"{t[i]:.6g}," + ",".join(f"{results[v][c][i]:.8g}" for v in C.VARIANTS for c in cols)
                     + f",{results['cs']['road_displacement'][i]:.8g},"
                     + ",".join(f"{results[v][c][i]:.8g}" for v in C.VARIANTS for c in extra) + "\n")

    rows = {v: C.rms_row(results[v]) for v in C.VARIANTS}
    field = {v: C.field_row(results[v]) for v in C.VARIANTS}
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(13, 12), constrained_layout=True)
    gs = fig.add_gridspec(5, 1, height_ratios=[1, 1, 1, 0.62, 0.62])
    specs = [("body_acceleration", 1.0, "BA (m/s²)", "body acceleration"),
             ("suspension_deflection", 1.0, "SDD = x_s − x_t (m)", "suspension dynamic deflection"),
             ("tire_deflection", 1e3, "TDD = x_t − x_g (mm)", "tire dynamic displacement")]
    axes = []
    for k, (name, scale, ylabel, title) in enumerate(specs):
        ax = fig.add_subplot(gs[k], sharex=axes[0] if axes else None)
        for v in C.VARIANTS:
            ax.plot(t, scale * results[v][name], color=C.COLORS[v], lw=1.2,
                    label=f"{C.LABELS[v]} (RMS {rows[v][k]:.4g})")
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=10.5, loc="left")
        ax.grid(True, alpha=0.3)
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi + 0.3 * (hi - lo))  # room for the legend
        ax.legend(loc="upper right", fontsize=8.5, ncol=3)
        axes.append(ax)
    axes[-1].set_xlabel("time t (s)")
    axes[-1].set_xlim(0, args.duration)

    tab = fig.add_subplot(gs[3])
    tab.axis("off")
    cell, colors = [], []
    for v in C.VARIANTS:
        row, crow = [C.LABELS[v]], ["0.92"]
        for k in range(3):
            ours, paper = rows[v][k], C.TABLE2[v][k]
            row.append(f"{ours:.4f}  |  {paper:.4f}  ({C.pct(ours, paper)})")
            crow.append("#dff0d8" if abs(ours - paper) <= 0.005 * abs(paper) else "#fcf8e3")
        cell.append(row)
        colors.append(crow)
    table = tab.table(cellText=cell, cellColours=colors,
                      colLabels=["RMS: tdvass | paper", "BA (m/s²)", "SDD (m)", "TDD (mm)"],
                      loc="center", cellLoc="center")
    table.auto_set_font_size(False)
    table.set_fontsize(10)
    table.scale(1, 1.7)
    tab.set_title("Table 2, RMS over 0–15 s from rest (green: within 0.5 % of the paper)", fontsize=10.5)

    tab = fig.add_subplot(gs[4])
    tab.axis("off")
    cell = [[C.LABELS[v], f"{field[v][0]:.4f} ({C.comfort_reaction(field[v][0])})",
             *(f"{x:.4f}" for x in field[v][1:])] for v in C.VARIANTS]
    table = tab.table(cellText=cell, colLabels=["field metrics", "a_w (m/s²), ISO 2631-1", "VDV (m/s^1.75)",
                                                "RMS tire load / static", "contact loss (s)", "max |SDD| (m)"],
                      colWidths=[0.12, 0.28, 0.15, 0.15, 0.15, 0.15], loc="center", cellLoc="center")
    table.auto_set_font_size(False)
    table.set_fontsize(10)
    table.scale(1, 1.7)
    tab.set_title("not in the paper: W_k-weighted comfort (ISO 2631-1), road holding, working space",
                  fontsize=10.5)
    fig.suptitle(f"Harmonic road x_g = 0.05 sin(5t), from rest; TDVASS g1 = {C.G1:g} N/m, "
                 f"τ1 = {C.TAU1:g} s; Table 1 parameters (paper Fig. 11, Table 2); fmpy + tdvass.fmu")
    C.save_figure(fig, out, "table2")

    lines = [f"Table 2: harmonic road 0.05 sin(5t), {args.duration:g} s from rest, RMS over the whole run",
             f"TDVASS g1 = {C.G1:g} N/m, tau1 = {C.TAU1:g} s; FMU running-RMS outputs at t = {t[-1]:g} s",
             "", f"{'variant':<8}" + "".join(f"{m:>14}{'paper':>9}{'diff':>9}" for m in C.METRICS_ASCII)]
    for v in C.VARIANTS:
        line = f"{C.LABELS[v]:<8}"
        for k in range(3):
            ours, paper = rows[v][k], C.TABLE2[v][k]
            line += f"{ours:>14.4f}{paper:>9.4f}{C.pct(ours, paper):>9}"
        lines.append(line)
    lines.append("")
    for v in C.VARIANTS:
        lines.append(f"{C.LABELS[v]}: J = {results[v]['objective'][-1]:.6f}")
    lines += ["", "field metrics (not in the paper), over the same run:",
              "  a_w: ISO 2631-1 W_k-weighted RMS body acceleration; VDV = (integral of the weighted BA^4 dt)^(1/4);",
              "  tire load ratio: RMS dynamic tire load / static load (<= 1/3 keeps the contact at 3 sigma);",
              "  contact loss: time with the dynamic tire load below -static load (the linear model is then invalid)",
              f"{'variant':<8}" + "".join(f"{h:>18}" for h in C.FIELD_METRICS.values()) + "  comfort (ISO 2631-1)"]
    for v in C.VARIANTS:
        lines.append(f"{C.LABELS[v]:<8}" + "".join(f"{x:>18.4f}" for x in field[v])
                     + f"  {C.comfort_reaction(field[v][0])}")
    lines.append("")
    worst = max(abs(rows[v][k] - C.TABLE2[v][k]) / C.TABLE2[v][k] for v in C.VARIANTS for k in range(3))
    lines.append(f"largest relative difference from the paper: {100 * worst:.2f} %")
    C.write_summary(out, "table2", "\n".join(lines))


if __name__ == "__main__":
    main()
