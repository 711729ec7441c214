"""Table 2 through Model Exchange: fmpy's CVODE integrates the FMU's states, next to the exact co-simulation.

The paper's harmonic road x_g = 0.05 sin 5t, 15 s from rest, CS, PVASS and
TDVASS (g1 = 5386 N/m, tau1 = 2e-4 s). The same FMU runs twice per variant:
as Co-Simulation (the precise integration, exact to the tolerance) and as
Model Exchange (fmpy's CVODE, relative tolerance 1e-8, integrating the plant,
the W_k filter and the integrals behind the RMS outputs; the delay comes
from the FMU's history of the solver's points). Writes
table2_model_exchange.png (the running RMS of BA from both, and their
relative difference) and table2_model_exchange.txt (RMS BA, SDD, TDD of
both next to the paper's).

    python examples/table2_model_exchange.py [--quick] [--out out] [--fmu path/to/tdvass.fmu]
"""

from __future__ import annotations

import fmpy
import numpy as np

import _common as C

RMS = ["rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection"]


def run(fmu: str, variant: int, duration: float, interface: str):
    options = {"solver": "CVode", "relative_tolerance": 1e-8} if interface == "ModelExchange" else {}
    return fmpy.simulate_fmu(fmu, fmi_type=interface, stop_time=duration, output_interval=0.01,
                             start_values={"variant": variant, "g": C.G1, "tau": C.TAU1},
                             output=RMS, **options)


def main() -> None:
    p = C.parser(__doc__.splitlines()[0])
    p.add_argument("--fmu", default=None, help="FMU path (default $TDVASS_FMU or target/fmu/tdvass.fmu)")
    args = p.parse_args()
    out = C.prepare_out(args.out)
    fmu = args.fmu or C.fmu_path()
    duration = 3.0 if args.quick else 15.0

    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    lines = [f"Table 2 over {duration:g} s: Model Exchange (fmpy CVODE, rtol 1e-8) and Co-Simulation",
             f"{'variant':8s} {'interface':15s} " + " ".join(f"{m:>12s}" for m in C.METRICS_ASCII)]
    largest = 0.0
    for name, code in C.VARIANTS.items():
        me = run(fmu, code, duration, "ModelExchange")
        cs = run(fmu, code, duration, "CoSimulation")
        for label, r in (("ModelExchange", me), ("CoSimulation", cs)):
            values = (r[RMS[0]][-1], r[RMS[1]][-1], 1e3 * r[RMS[2]][-1])
            lines.append(f"{C.LABELS[name]:8s} {label:15s} " + " ".join(f"{v:12.4f}" for v in values))
        lines.append(f"{C.LABELS[name]:8s} {'paper':15s} " + " ".join(f"{v:12.4f}" for v in C.TABLE2[name]))
        difference = max(abs(me[k][-1] / cs[k][-1] - 1) for k in RMS)
        largest = max(largest, difference)
        top.plot(cs["time"], cs[RMS[0]], color=C.COLORS[name], label=f"{C.LABELS[name]} co-simulation")
        top.plot(me["time"], me[RMS[0]], color=C.COLORS[name], ls="--", label=f"{C.LABELS[name]} Model Exchange")
        t = cs["time"][1:]
        relative = np.abs(me[RMS[0]][1:] / cs[RMS[0]][1:] - 1)
        bottom.semilogy(t, np.maximum(relative, 1e-16), color=C.COLORS[name], label=C.LABELS[name])
    lines.append(f"largest relative difference Model Exchange / Co-Simulation at the end: {largest:.2e}")
    top.set_ylabel("running RMS of BA (m/s²)")
    top.legend(fontsize=8)
    bottom.set_ylabel("|ME / CS − 1| of RMS BA")
    bottom.set_xlabel("time (s)")
    bottom.legend(fontsize=8)
    fig.tight_layout()
    C.save_figure(fig, out, "table2_model_exchange")
    C.write_summary(out, "table2_model_exchange", "\n".join(lines))


if __name__ == "__main__":
    main()
