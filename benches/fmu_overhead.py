#!/usr/bin/env python3
"""15 s of TDVASS (defaults: Table 1, g1/tau1, harmonic road) through the
FMU driven by fmpy at a 1 ms communication step, next to a trivial FMU-call
baseline measured in the same run, so that the FMU's own share is visible.

Loops, each over the same number of communication points (15 000):
  doStep + getReal   what a master does: one step, then read the outputs
  doStep only        the FMU's work plus one ctypes call per point
  getReal only       the baseline: one ctypes call into the FMU that does
                     no simulation (copies 15 outputs)
  simulate_fmu       fmpy's one-call driver (output_interval 1 ms), for
                     reference
  doStep + getReal(3), t = k h / t += h
                     a typical script: one step, then three outputs, with
                     the communication time computed or accumulated (the
                     two must cost about the same)

Per communication step the FMU advances 10 internal steps of 1e-4 s.

Usage: benches/fmu_overhead.py [--fmu PATH] [--repeats N] [--duration S]
The FMU is target/fmu/tdvass.fmu (build: cargo run --release -p fmu-build).
"""

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave

ROOT = Path(__file__).resolve().parent.parent
OUTPUTS = [
    "x_s", "v_s", "x_h", "v_h", "x_t", "v_t", "body_acceleration",
    "suspension_deflection", "tire_deflection", "road_displacement",
    "control_force", "rms_body_acceleration", "rms_suspension_deflection",
    "rms_tire_deflection", "objective",
]


def default_fmu():
    target = os.environ.get("CARGO_TARGET_DIR")
    target_dir = Path(target) if target else ROOT / "target"
    return target_dir / "fmu" / "tdvass.fmu"


def new_slave(md, unzipdir):
    slave = FMU2Slave(
        guid=md.guid, unzipDirectory=unzipdir,
        modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench",
    )
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave


def run_loop(md, unzipdir, refs, n, dt, step, read, accumulate=False):
    slave = new_slave(md, unzipdir)
    last = None
    start = time.perf_counter()
    t = 0.0
    for i in range(n):
        if step:
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=dt)
            t = t + dt if accumulate else (i + 1) * dt
        if read:
            last = slave.getReal(refs)
    seconds = time.perf_counter() - start
    slave.terminate()
    slave.freeInstance()
    return seconds, last


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--fmu", default=str(default_fmu()))
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--duration", type=float, default=15.0)
    parser.add_argument("--step", type=float, default=1e-3)
    args = parser.parse_args()
    md = read_model_description(args.fmu)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    refs = [vr[name] for name in OUTPUTS]
    n = int(round(args.duration / args.step))
    print(f"FMU {args.fmu}: {n} communication steps of {args.step * 1e3:g} ms, "
          f"median of {args.repeats} runs")
    with tempfile.TemporaryDirectory() as tmp:
        unzipdir = extract(args.fmu, unzipdir=tmp)
        three = [vr[name] for name in ("body_acceleration", "rms_body_acceleration", "objective")]
        loops = {
            "doStep + getReal": (True, True, refs, False),
            "doStep only": (True, False, refs, False),
            "getReal only (baseline)": (False, True, refs, False),
            "doStep + getReal(3), t=kh": (True, True, three, False),
            "doStep + getReal(3), t+=h": (True, True, three, True),
        }
        times = {name: [] for name in loops}
        outputs = None
        for _ in range(args.repeats):
            for name, (step, read, which, accumulate) in loops.items():
                seconds, last = run_loop(md, unzipdir, which, n, args.step, step, read, accumulate)
                times[name].append(seconds)
                if step and read and which is refs:
                    outputs = last
        fmpy_times = []
        for _ in range(max(1, args.repeats // 2)):
            start = time.perf_counter()
            simulate_fmu(args.fmu, stop_time=args.duration, step_size=args.step,
                         output_interval=args.step, output=OUTPUTS)
            fmpy_times.append(time.perf_counter() - start)
    medians = {name: statistics.median(v) for name, v in times.items()}
    for name, seconds in medians.items():
        print(f"  {name:26s} {seconds * 1e3:9.1f} ms total  {seconds / n * 1e6:7.2f} us/step")
    share = medians["doStep + getReal"] - medians["getReal only (baseline)"]
    print(f"  {'FMU share (difference)':26s} {share * 1e3:9.1f} ms total  {share / n * 1e6:7.2f} us/step")
    ratio = medians["doStep + getReal(3), t+=h"] / medians["doStep + getReal(3), t=kh"]
    print(f"  {'accumulated / exact times':26s} {ratio:9.3f}")
    seconds = statistics.median(fmpy_times)
    print(f"  {'fmpy simulate_fmu':26s} {seconds * 1e3:9.1f} ms total  {seconds / n * 1e6:7.2f} us/step")
    rms = dict(zip(OUTPUTS, outputs))
    print(f"  at {args.duration} s: RMS BA {rms['rms_body_acceleration']:.4f}, "
          f"SDD {rms['rms_suspension_deflection']:.4f}, "
          f"TDD {rms['rms_tire_deflection'] * 1e3:.4f} mm (Table 2: 0.3068, 0.0388, 0.6251)")


if __name__ == "__main__":
    main()
