"""The full car: the chassis FMU on four corner FMUs, from full-car.ssp.

Reads the system from the SSD inside target/fmu/full-car.ssp (the five
instances `chassis`, `fl`, `fr`, `rl`, `rr`, each corner's road
parameters, the twelve connections) and steps the five FMUs with fmpy in a
loop, as libcosim's and ecos's fixed-step algorithms do (Jacobi): after
each step every output is read, then every input set, then every FMU
steps. fmpy's own `simulate_ssp` applies no parameters of an SSD, so the
loop applies them itself.

Every corner rolls on the ISO 8608 class C road at the default 20 m/s; the
rear wheels see their front wheel's road a wheelbase later, and the right
track has a road of its own (the next seed), so the car pitches and rolls.
Writes

- full_car.png: heave, pitch and roll, and the four suspension
  deflections, over the run;
- full_car.txt: the chassis's RMS heave, pitch and roll accelerations, the
  seat's W_k-weighted RMS acceleration and VDV, and each corner's RMS
  suspension deflection, dynamic tire load ratio and lift-off count.

    python examples/full_car.py [--quick] [--out out] [--duration S] [--step H]
"""

from __future__ import annotations

import shutil
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np

import _common as C

CORNERS = ["fl", "fr", "rl", "rr"]
CHASSIS_TRACES = ["heave", "pitch", "roll"]
CORNER_TRACES = ["suspension_deflection"]
CHASSIS_SUMMARY = ["rms_heave_acceleration", "rms_pitch_acceleration", "rms_roll_acceleration",
                   "rms_weighted_seat_acceleration", "seat_vibration_dose_value"]
CORNER_SUMMARY = ["rms_suspension_deflection", "rms_dynamic_tire_load_ratio", "rms_tire_deflection"]

SSD = "{http://ssp-standard.org/SSP1/SystemStructureDescription}"
SSV = "{http://ssp-standard.org/SSP1/SystemStructureParameterValues}"


def ssp_path() -> Path:
    return Path(C.fmu_path()).parent / "full-car.ssp"


def read_ssd(ssp: Path):
    """The components `{instance: (FMU entry, {parameter: value})}` and the
    connections `[(from, output, to, input)]` of the SSD in `ssp`."""
    with zipfile.ZipFile(ssp) as archive:
        root = ET.fromstring(archive.read("SystemStructure.ssd"))
    components = {}
    for component in root.iter(f"{SSD}Component"):
        parameters = {}
        for parameter in component.iter(f"{SSV}Parameter"):
            for kind, cast in (("Real", float), ("Integer", int)):
                value = parameter.find(f"{SSV}{kind}")
                if value is not None:
                    parameters[parameter.get("name")] = cast(value.get("value"))
        components[component.get("name")] = (component.get("source"), parameters)
    connections = [
        (c.get("startElement"), c.get("startConnector"), c.get("endElement"), c.get("endConnector"))
        for c in root.iter(f"{SSD}Connection")
    ]
    return components, connections


def run_car(ssp: Path, stop_time: float, step: float, traces: dict | None = None, overrides: dict | None = None):
    """Runs the car of `ssp` to `stop_time` in steps of `step` (Jacobi).

    `traces`: `{instance: [output, ...]}` recorded at every communication
    point. `overrides`: `{instance: {parameter: value}}` set after the
    SSD's parameters, so they win (a different chassis, road or tire).
    Returns `(times, {(instance, output): values}, summary)`, the
    summary the chassis's and corners' outputs at the end."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    components, connections = read_ssd(ssp)
    unknown = set(overrides or {}) - set(components)
    if unknown:
        raise ValueError(f"no instance {sorted(unknown)} in {ssp}")
    n = round(stop_time / step)
    traces = traces or {}
    work = Path(tempfile.mkdtemp())
    try:
        with zipfile.ZipFile(ssp) as archive:
            archive.extractall(work)
        slaves, refs = {}, {}
        for instance, (source, parameters) in components.items():
            fmu = work / source
            description = read_model_description(str(fmu))
            slave = FMU2Slave(guid=description.guid, unzipDirectory=extract(str(fmu), unzipdir=str(work / instance)),
                              modelIdentifier=description.coSimulation.modelIdentifier, instanceName=instance)
            slave.instantiate()
            slave.setupExperiment(startTime=0.0, stopTime=n * step)
            refs[instance] = {v.name: (v.valueReference, v.type) for v in description.modelVariables}
            for name, value in {**parameters, **(overrides or {}).get(instance, {})}.items():
                vr, kind = refs[instance][name]
                if kind == "Integer":
                    slave.setInteger([vr], [int(value)])
                else:
                    slave.setReal([vr], [float(value)])
            slave.enterInitializationMode()
            slave.exitInitializationMode()
            slaves[instance] = slave
        links = [(slaves[a], refs[a][out][0], slaves[b], refs[b][inp][0]) for a, out, b, inp in connections]

        def transfer():
            values = [source.getReal([vr])[0] for source, vr, _, _ in links]
            for (_, _, sink, vr), value in zip(links, values):
                sink.setReal([vr], [value])

        recorded = {(i, name): np.empty(n + 1) for i, names in traces.items() for name in names}

        def record(k):
            for (i, name), values in recorded.items():
                values[k] = slaves[i].getReal([refs[i][name][0]])[0]

        transfer()
        record(0)
        for k in range(n):
            for slave in slaves.values():
                slave.doStep(currentCommunicationPoint=k * step, communicationStepSize=step)
            transfer()
            record(k + 1)

        def real(i, name):
            return slaves[i].getReal([refs[i][name][0]])[0]

        summary = {
            "chassis": {name: real("chassis", name) for name in CHASSIS_SUMMARY},
            "corners": {
                c: {**{name: real(c, name) for name in CORNER_SUMMARY},
                    "lift_off_count": slaves[c].getInteger([refs[c]["lift_off_count"][0]])[0]}
                for c in CORNERS
            },
        }
        for slave in slaves.values():
            slave.terminate()
            slave.freeInstance()
        return np.arange(n + 1) * step, recorded, summary
    finally:
        shutil.rmtree(work, ignore_errors=True)


def main() -> None:
    p = C.parser(__doc__.splitlines()[0])
    p.add_argument("--duration", type=float, default=None, help="simulated time (s); default 5 (1 with --quick)")
    p.add_argument("--step", type=float, default=1e-3, help="communication step (s)")
    args = p.parse_args()
    out = C.prepare_out(args.out)
    duration = args.duration or (1.0 if args.quick else 5.0)
    ssp = ssp_path()
    if not ssp.is_file():
        raise SystemExit(f"{ssp} not found; build it with `cargo run --release -p fmu-build`")
    traces = {"chassis": CHASSIS_TRACES, **{c: CORNER_TRACES for c in CORNERS}}
    times, recorded, summary = run_car(ssp, duration, args.step, traces)

    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    body = axes[0]
    body.plot(times, 1e3 * recorded[("chassis", "heave")], label="heave z (mm)")
    body.plot(times, 1e3 * recorded[("chassis", "pitch")], label="pitch θ (mrad)")
    body.plot(times, 1e3 * recorded[("chassis", "roll")], label="roll φ (mrad)")
    body.set_title(f"The body: ISO 8608 class C at 20 m/s, {duration:g} s, {args.step * 1e3:g} ms steps")
    body.legend(loc="upper right")
    body.grid(alpha=0.3)
    for c in CORNERS:
        axes[1].plot(times, 1e3 * recorded[(c, "suspension_deflection")], label=c)
    axes[1].set_title("Suspension deflection of each corner (mm)")
    axes[1].set_xlabel("time (s)")
    axes[1].legend(loc="upper right", ncol=4)
    axes[1].grid(alpha=0.3)
    fig.tight_layout()
    C.save_figure(fig, out, "full_car")

    lines = [f"The full car, fmpy loop over full-car.ssp, {duration:g} s in steps of {args.step:g} s", ""]
    lines += [f"  {name:34s} {value:.6g}" for name, value in summary["chassis"].items()]
    lines += ["", f"  {'corner':8s}" + "".join(f"{name:>30s}" for name in [*CORNER_SUMMARY, "lift_off_count"])]
    for c, values in summary["corners"].items():
        lines.append(f"  {c:8s}" + "".join(f"{v:>30.6g}" for v in values.values()))
    print(C.write_summary(out, "full_car", "\n".join(lines) + "\n").read_text())


if __name__ == "__main__":
    main()
