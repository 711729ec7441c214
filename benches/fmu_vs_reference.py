#!/usr/bin/env python3
"""tdvass.fmu against the FMI project's Reference FMU Dahlquist in the same
master loop and the same run: fmpy's FMU2Slave, `doStep` then `getReal` of
three variables, 15 s of 1 ms steps (15 000 points), median of the repeats.

Dahlquist (one state, explicit Euler) is the cheapest model an FMU can be,
so the ratio is what tdvass adds to what the master itself costs.

Usage: benches/fmu_vs_reference.py [--fmu PATH ...] [--reference PATH]
                                   [--outputs rms|instantaneous] [--step S]
                                   [--repeats N] [--duration S]
Defaults: target/fmu/tdvass.fmu (cargo run --release -p fmu-build) and
../shared/ref-fmus/Dahlquist.fmu beside the repository; the three RMS
values (time averages), 1 ms steps.

`--outputs instantaneous` reads BA, SDD and TDD instead. `--fmu` may be
given more than once (another build of the FMU, say): each repeat runs
every FMU and Dahlquist in turn, so all are timed under the same load, and
each FMU's ratio is printed, also as the median of its ratios to the
Dahlquist run of the same repeat.
"""

import argparse
import math
import statistics
import tempfile
import time
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

ROOT = Path(__file__).resolve().parent.parent
TDVASS_OUTPUTS = {
    "rms": ["rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection"],
    "instantaneous": ["body_acceleration", "suspension_deflection", "tire_deflection"],
}
DAHLQUIST_VARIABLES = ["x", "der(x)", "k"]


def start(path, workdir, road_input=False):
    md = read_model_description(str(path))
    unzipdir = extract(str(path), unzipdir=tempfile.mkdtemp(dir=workdir))
    slave = FMU2Slave(
        guid=md.guid,
        unzipDirectory=unzipdir,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="bench",
    )
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    if road_input:
        by_name = {v.name: v.valueReference for v in md.modelVariables}
        slave.setInteger([by_name["road"], by_name["input_extrapolation"]], [0, 2])
    slave.exitInitializationMode()
    return md, slave


def road_input_value(t):
    """The x_g (m) the road-input loop sets at time t (s)."""
    return 0.02 * math.sin(9 * t) + 0.004 * math.sin(60 * t)


def loop(path, names, duration, step, workdir, road_input=False):
    """Seconds per communication point of `doStep` + `getReal(names)`; with
    `road_input` (tdvass only: `road` = 0, `input_extrapolation` = 2) the
    master sets `x_g` before each step."""
    md, slave = start(path, workdir, road_input)
    by_name = {v.name: v.valueReference for v in md.modelVariables}
    vrs = [by_name[n] for n in names]
    x_g = [by_name["x_g"]] if road_input else None
    n = int(round(duration / step))
    begin = time.perf_counter()
    for k in range(n):
        if x_g:
            slave.setReal(x_g, [road_input_value(k * step)])
        slave.doStep(currentCommunicationPoint=k * step, communicationStepSize=step)
        slave.getReal(vrs)
    seconds = (time.perf_counter() - begin) / n
    slave.terminate()
    slave.freeInstance()
    return seconds


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--fmu", action="append")
    parser.add_argument(
        "--reference", default=str(ROOT.parent / "shared" / "ref-fmus" / "Dahlquist.fmu")
    )
    parser.add_argument("--outputs", choices=sorted(TDVASS_OUTPUTS), default="rms")
    parser.add_argument("--step", type=float, default=1e-3)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--duration", type=float, default=15.0)
    args = parser.parse_args()
    fmus = args.fmu or [str(ROOT / "target" / "fmu" / "tdvass.fmu")]
    names = TDVASS_OUTPUTS[args.outputs]
    ours = {fmu: [] for fmu in fmus}
    theirs = []
    with tempfile.TemporaryDirectory() as workdir:
        for _ in range(args.repeats):
            for fmu in fmus:
                ours[fmu].append(loop(fmu, names, args.duration, args.step, workdir))
            theirs.append(
                loop(args.reference, DAHLQUIST_VARIABLES, args.duration, args.step, workdir)
            )
    b = statistics.median(theirs)
    print(
        f"doStep({args.step * 1e3:g} ms) + getReal(3 {args.outputs}), "
        f"median of {args.repeats} runs of {args.duration} s:"
    )
    for fmu, times in ours.items():
        a = statistics.median(times)
        paired = statistics.median(t / r for t, r in zip(times, theirs))
        print(f"  {fmu}")
        print(f"    tdvass        {a * 1e6:8.3f} us per point")
        print(f"    ratio         {a / b:8.3f}  (median of the paired ratios {paired:.3f})")
    print(f"  Dahlquist.fmu   {b * 1e6:8.3f} us per point")


if __name__ == "__main__":
    main()
