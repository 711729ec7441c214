#!/usr/bin/env python3
"""Model Exchange cost: tdvass.fmu against the FMI project's Reference FMU
VanDerPol (two states) in the same master loop and the same run.

Two measurements, each the median of the repeats, both FMUs timed in turn
under the same load:
- `derivatives`: fmpy's FMU2Model, N times `fmi2SetTime`,
  `fmi2SetContinuousStates`, `fmi2GetDerivatives` at increasing times (the
  calls a solver makes per right-hand side), time per triple;
- `cvode`: `fmpy.simulate_fmu(fmi_type='ModelExchange', solver='CVode')`,
  relative tolerance 1e-8, output every 10 ms, DURATION s (tdvass: the
  TDVASS on the paper's harmonic road, tau = 0.011 s), wall time and
  derivative evaluations.

Usage: benches/model_exchange.py [--fmu PATH] [--reference PATH]
                                 [--calls N] [--repeats R] [--duration S]
Defaults: target/fmu/tdvass.fmu, ../shared/ref-fmus/VanDerPol.fmu,
20000 calls, 5 repeats, 3 s.
"""

import argparse
import statistics
import tempfile
import time
from ctypes import c_double
from pathlib import Path

import fmpy
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model

ROOT = Path(__file__).resolve().parent.parent


def model(path, workdir):
    md = read_model_description(str(path))
    unzipdir = extract(str(path), unzipdir=tempfile.mkdtemp(dir=workdir))
    fmu = FMU2Model(guid=md.guid, unzipDirectory=unzipdir,
                    modelIdentifier=md.modelExchange.modelIdentifier, instanceName="bench")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    return fmu, md.numberOfContinuousStates


def derivative_calls(path, workdir, calls):
    fmu, n = model(path, workdir)
    x = (c_double * n)()
    dx = (c_double * n)()
    fmu.getContinuousStates(x, n)
    begin = time.perf_counter()
    for i in range(calls):
        fmu.setTime(i * 1e-4)
        fmu.setContinuousStates(x, n)
        fmu.getDerivatives(dx, n)
    elapsed = time.perf_counter() - begin
    fmu.terminate()
    fmu.freeInstance()
    return elapsed / calls


def cvode_run(path, duration, start_values):
    evaluations = [0]

    def count(line):
        if "GetDerivatives" in line:
            evaluations[0] += 1

    begin = time.perf_counter()
    fmpy.simulate_fmu(str(path), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-8,
                      stop_time=duration, output_interval=0.01, start_values=start_values,
                      fmi_call_logger=count)
    return time.perf_counter() - begin, evaluations[0]


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fmu", default=str(ROOT / "target" / "fmu" / "tdvass.fmu"))
    p.add_argument("--reference", default=str(ROOT.parent / "shared" / "ref-fmus" / "VanDerPol.fmu"))
    p.add_argument("--calls", type=int, default=20000)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--duration", type=float, default=3.0)
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as workdir:
        per_call = {"tdvass": [], "VanDerPol": []}
        runs = {"tdvass": [], "VanDerPol": []}
        for _ in range(args.repeats):
            per_call["tdvass"].append(derivative_calls(args.fmu, workdir, args.calls))
            per_call["VanDerPol"].append(derivative_calls(args.reference, workdir, args.calls))
            runs["tdvass"].append(cvode_run(args.fmu, args.duration, {"variant": 3, "tau": 0.011}))
            runs["VanDerPol"].append(cvode_run(args.reference, args.duration, {}))
    t, v = statistics.median(per_call["tdvass"]), statistics.median(per_call["VanDerPol"])
    print(f"SetTime + SetContinuousStates + GetDerivatives ({args.calls} calls, median of {args.repeats}):")
    print(f"  tdvass {t * 1e6:.2f} us, VanDerPol {v * 1e6:.2f} us, ratio {t / v:.2f}")
    print(f"fmpy CVODE, rtol 1e-8, {args.duration} s (median of {args.repeats}):")
    for name, samples in runs.items():
        seconds = statistics.median(s for s, _ in samples)
        print(f"  {name}: {seconds:.3f} s, {samples[0][1]} derivative evaluations, "
              f"{seconds / samples[0][1] * 1e6:.1f} us per evaluation")


if __name__ == "__main__":
    main()
