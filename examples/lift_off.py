"""Wheel lift-off: the paper's bilateral tire against a unilateral one.

The paper's linear tire pulls the wheel down when the dynamic tire load
k_t (x_g - x_t) falls below minus the static load W; a real tire cannot, and
the wheel lifts off. The FMU's parameter tire_contact = 1 makes the tire
unilateral: the wheel flies under the suspension forces and -W until it
touches down, the switches located inside the steps.

Runs the FMU with fmpy on ISO 8608 roads (20 m/s, road seed 1) for CS, PVASS
and TDVASS (g2 = 2528 N/m, tau2 = 1.28e-4 s) under both tire models. Writes

- lift_off.png: the total tire force W + dynamic tire load of TDVASS on a
  class D road over 3 s under both models, the flight phases of the
  unilateral tire shaded;
- lift_off.csv and lift_off.txt: per class C, D, E, variant and tire model,
  RMS BA, SDD, TDD, J, a_w, the time without contact and the number of
  lift-offs.

    python examples/lift_off.py [--quick] [--out out]
"""

from __future__ import annotations

import numpy as np

import _common as C

TIRES = {0: "bilateral", 1: "unilateral"}
CLASSES = {3: "C", 4: "D", 5: "E"}
TABLE_OUTPUTS = ["rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection", "objective",
                 "rms_weighted_body_acceleration", "contact_loss_time"]
HEADERS = ["RMS BA (m/s^2)", "RMS SDD (m)", "RMS TDD (m)", "J", "a_w (m/s^2)", "no contact (s)", "lift-offs"]


def static_load(variant: str) -> float:
    masses = C.TABLE1["m_s"] + C.TABLE1["m_t"] + (0.0 if variant == "cs" else C.TABLE1["m_h"])
    return masses * C.G0


def main() -> None:
    p = C.parser(__doc__.splitlines()[0])
    p.add_argument("--fmu", default=None, help="FMU path (default $TDVASS_FMU or target/fmu/tdvass.fmu)")
    p.add_argument("--duration", type=float, default=None, help="simulated time (s); default 15 (3 with --quick)")
    args = p.parse_args()
    out = C.prepare_out(args.out)
    duration = args.duration or (3.0 if args.quick else 15.0)
    step = 1e-3

    rows = []
    traces = {}
    with C.FmuRunner(args.fmu) as fmu:
        for road_class, klass in CLASSES.items():
            for variant, code in C.VARIANTS.items():
                for tire, tire_name in TIRES.items():
                    params = {"variant": code, "road": 2, "road_class": road_class, "road_seed": 1,
                              "vehicle_speed": 20.0, "g": C.G2, "tau": C.TAU2, "tire_contact": tire}
                    r = fmu.run(params, duration, step, [*TABLE_OUTPUTS, "dynamic_tire_load"])
                    if r["error"]:
                        raise SystemExit(f"class {klass}, {variant}, {tire_name}: {r['error']}")
                    lift_offs = fmu.get("lift_off_count")
                    rows.append((klass, variant, tire_name, *(r[name][-1] for name in TABLE_OUTPUTS), lift_offs))
                    if klass == "D" and variant == "tdvass":
                        traces[tire_name] = (r["time"], r["dynamic_tire_load"])
            print(f"class {klass} done")

    with open(out / "lift_off.csv", "w") as fh:
        fh.write("road_class,variant,tire_contact," + ",".join(TABLE_OUTPUTS) + ",lift_off_count\n")
        for klass, variant, tire, *values in rows:
            fh.write(f"{klass},{variant},{tire}," + ",".join(f"{v:.8g}" for v in values[:-1])
                     + f",{values[-1]}\n")
    lines = [f"ISO 8608 roads at 20 m/s, seed 1, {duration:g} s from rest; TDVASS g2 = {C.G2:g} N/m, "
             f"tau2 = {C.TAU2:g} s",
             f"{'class':<6}{'variant':<8}{'tire':<12}" + "".join(f"{h:>16}" for h in HEADERS)]
    for klass, variant, tire, *values in rows:
        lines.append(f"{klass:<6}{C.LABELS[variant]:<8}{tire:<12}"
                     + "".join(f"{v:>16.5g}" for v in values[:-1]) + f"{values[-1]:>16d}")
    C.write_summary(out, "lift_off", "\n".join(lines))

    import matplotlib.pyplot as plt

    weight = static_load("tdvass")
    shown = min(3.0, duration)
    fig, ax = plt.subplots(figsize=(11, 4.8), constrained_layout=True)
    for tire_name, style in (("bilateral", dict(color="tab:gray", lw=0.9)),
                             ("unilateral", dict(color="tab:green", lw=1.1))):
        t, load = traces[tire_name]
        keep = t <= shown
        ax.plot(t[keep], (weight + load[keep]) / 1e3, label=f"{tire_name} tire", **style)
    t, load = traces["unilateral"]
    flying = (weight + load) <= 1e-9 * weight
    ax.fill_between(t, 0, 1, where=flying & (t <= shown), transform=ax.get_xaxis_transform(),
                    color="tab:red", alpha=0.18, step="mid", label="flight (unilateral)")
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xlim(0, shown)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("total tire force W + k_t (x_g − x_t) (kN)")
    ax.set_title(f"TDVASS on an ISO 8608 class D road at 20 m/s: the bilateral tire pulls (force < 0), "
                 f"the unilateral one lets the wheel fly (W = {weight:.0f} N)", fontsize=10)
    ax.legend(loc="upper right", fontsize=9)
    ax.grid(True, alpha=0.3)
    C.save_figure(fig, out, "lift_off")


if __name__ == "__main__":
    main()
