"""Amplitude-frequency characteristics of CS, PVASS and TDVASS (paper Fig. 14).

|X_s/X_g| (body displacement, Eq. 4) and |A_s/X_g| (body acceleration,
Eq. 5) from `tdvass frf`, with TDVASS at the random-road controller
(g2, tau2) = (2528 N/m, 1.28e-4 s). Writes frequency_response.png,
frequency_response.csv (all three curves) and frequency_response.txt
(the resonance peaks, and the static gain X_s/X_g(0) = 1 - g/k_h that the
absolute tire-displacement feedback causes).

    python examples/frequency_response.py [--quick] [--out out]
"""

from __future__ import annotations

import numpy as np

import _common as C


def main() -> None:
    p = C.parser(__doc__.splitlines()[0])
    p.add_argument("--g", type=float, default=C.G2, help="TDVASS gain (N/m)")
    p.add_argument("--tau", type=float, default=C.TAU2, help="TDVASS delay (s)")
    p.add_argument("--f-min", type=float, default=0.01, help="lowest frequency (Hz)")
    p.add_argument("--f-max", type=float, default=30.0, help="highest frequency (Hz)")
    p.add_argument("--points", type=int, default=None, help="default 2000 (400 with --quick)")
    args = p.parse_args()
    out = C.prepare_out(args.out)
    points = args.points or (400 if args.quick else 2000)

    curves, peaks = {}, {}
    for v in C.VARIANTS:
        flags = ["--variant", v, "--g", args.g, "--tau", args.tau, "--f-min", args.f_min,
                 "--f-max", args.f_max, "--points", points]
        curves[v] = C.read_csv(C.cli("frf", *flags, json_output=False), from_text=True)
        peaks[v] = C.cli("frf", *flags)["peaks_hz"]

    f = curves["cs"]["frequency_hz"]
    with open(out / "frequency_response.csv", "w") as fh:
        fh.write("frequency_hz," + ",".join(f"{v}_body_displacement_gain,{v}_body_acceleration_gain"
                                            for v in C.VARIANTS) + "\n")
        for i in range(f.size):
            fh.write(f"{f[i]:.8g}," + ",".join(
                f"{curves[v]['body_displacement_gain'][i]:.8g},{curves[v]['body_acceleration_gain'][i]:.8g}"
                for v in C.VARIANTS) + "\n")

    import matplotlib.pyplot as plt

    labels = {"cs": "CS", "pvass": "PVASS (g = 0)",
              "tdvass": f"TDVASS (g = {args.g:g} N/m, τ = {args.tau:g} s)"}
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.2), constrained_layout=True)
    for ax, key, ylabel, name, logy in (
            (axes[0], "body_displacement_gain", "|X_s / X_g|  (–)", "body displacement (Eq. 4)", False),
            (axes[1], "body_acceleration_gain", "|A_s / X_g|  (1/s²)", "body acceleration (Eq. 5)", True)):
        for v in C.VARIANTS:
            ax.plot(f, curves[v][key], color=C.COLORS[v], lw=1.8, label=labels[v],
                    ls="--" if v == "pvass" else "-")
        ax.set_xscale("log")
        if logy:
            ax.set_yscale("log")
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel(ylabel)
        ax.set_title(f"{name}")
        ax.grid(True, which="both", alpha=0.3)
        ax.set_xlim(args.f_min, args.f_max)
    static = 1.0 - args.g / C.TABLE1["k_h"]
    axes[0].axhline(static, color=C.COLORS["tdvass"], ls=":", lw=1)
    axes[0].annotate(f"static gain 1 − g/k_h = {static:.3f}", (args.f_min * 1.3, static),
                     xytext=(0, -14), textcoords="offset points", color=C.COLORS["tdvass"], fontsize=9)
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=3)
    fig.suptitle("Amplitude-frequency characteristics, road displacement input (paper Fig. 14), "
                 "Table 1 parameters")
    C.save_figure(fig, out, "frequency_response")

    def fmt(xs):
        return ", ".join(f"{x:.3f}" for x in xs)

    lines = [f"Amplitude-frequency characteristics, Table 1 parameters; TDVASS g = {args.g:g} N/m, "
             f"tau = {args.tau:g} s; {points} log-spaced points in [{args.f_min:g}, {args.f_max:g}] Hz",
             "", f"{'variant':<8}{'BD peaks (Hz)':>26}{'BA peaks (Hz)':>26}{'|X_s/X_g| at ' + format(f[0], 'g') + ' Hz':>22}"]
    for v in C.VARIANTS:
        lines.append(f"{C.LABELS[v]:<8}{fmt(peaks[v]['body_displacement']):>26}"
                     f"{fmt(peaks[v]['body_acceleration']):>26}{curves[v]['body_displacement_gain'][0]:>22.4f}")
    for v in C.VARIANTS:
        bd = curves[v]["body_displacement_gain"]
        i = int(np.argmax(bd))
        lines.append(f"{C.LABELS[v]}: largest |X_s/X_g| = {bd[i]:.3f} at {f[i]:.3f} Hz")
    lines += ["",
              f"static body gain of TDVASS: 1 - g/k_h = {static:.4f} (the feedback uses the absolute tire",
              "displacement, so the body does not follow a constant road offset); CS and PVASS: 1.",
              "paper (section 5.3, qualitative): the low resonance of PVASS/TDVASS lies below that of CS,",
              "the high (wheel-hop) resonance is almost unchanged."]
    lo = {v: peaks[v]["body_displacement"][0] for v in C.VARIANTS if peaks[v]["body_displacement"]}
    if len(lo) == 3:
        ok = lo["pvass"] < lo["cs"] and lo["tdvass"] < lo["cs"]
        lines.append(f"low body resonance CS {lo['cs']:.3f} Hz, PVASS {lo['pvass']:.3f} Hz, "
                     f"TDVASS {lo['tdvass']:.3f} Hz: {'agrees' if ok else 'DISAGREES'}")
    C.write_summary(out, "frequency_response", "\n".join(lines))


if __name__ == "__main__":
    main()
