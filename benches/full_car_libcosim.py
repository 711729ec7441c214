#!/usr/bin/env python3
"""The five-FMU car in libcosim against libcosim's own floor, in the same
run: `full-car/OspSystemStructure.xml` (the chassis and four corners, 12
connections, fixed step 1 ms) and five instances of the FMI project's
Reference FMU Dahlquist (one state, explicit Euler: the cheapest model an
FMU can be) in a fixed-step execution of the same step, each simulated
for the same time, in turn, the fastest of the repeats.

Dahlquist has no inputs, so its five instances are not connected: the
baseline is libcosim stepping five FMUs, which is what its per-step
hand-over between worker threads costs; the ratio is what the car's FMUs
and connections add to it.

Usage: benches/full_car_libcosim.py [--duration S] [--repeats N]
Defaults: 60 s, 3 repeats; target/fmu (cargo run --release -p fmu-build)
and ../shared/ref-fmus/Dahlquist.fmu beside the repository.
"""

import argparse
import time
from pathlib import Path

from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimSlave import CosimLocalSlave

ROOT = Path(__file__).resolve().parent.parent
STEP_NS = 1_000_000  # 1 ms, the car's step in OspSystemStructure.xml


def car_execution() -> CosimExecution:
    return CosimExecution.from_osp_config_file(str(ROOT / "target" / "fmu" / "full-car" / "OspSystemStructure.xml"))


def baseline_execution(reference: Path) -> tuple[CosimExecution, list]:
    """Five Dahlquist instances at the car's step (the slaves are returned
    to keep them alive)."""
    execution = CosimExecution.from_step_size(step_size=STEP_NS)
    slaves = [CosimLocalSlave(fmu_path=str(reference), instance_name=f"dahlquist{i}") for i in range(5)]
    for slave in slaves:
        assert execution.add_local_slave(slave) >= 0, "libcosim could not add Dahlquist"
    return execution, slaves


def wall_time(execution: CosimExecution, duration: float) -> float:
    stop = round(duration * 1e9)
    start = time.perf_counter()
    assert execution.simulate_until(stop), "simulate_until failed"
    wall = time.perf_counter() - start
    assert execution.status().current_time == stop
    return wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=60.0, help="simulated time (s)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--reference", type=Path, default=ROOT.parent / "shared" / "ref-fmus" / "Dahlquist.fmu")
    args = parser.parse_args()
    # FATAL: FMI Library reports a start value Dahlquist's description
    # leaves out at level ERROR, once per instance and run.
    log_output_level(CosimLogLevel.FATAL)
    car, baseline = [], []
    for _ in range(args.repeats):
        car.append(wall_time(car_execution(), args.duration))
        execution, _slaves = baseline_execution(args.reference)
        baseline.append(wall_time(execution, args.duration))
    steps = round(args.duration * 1e9 / STEP_NS)
    for name, walls in [("full car (5 FMUs, 12 connections)", car), ("5 x Dahlquist (libcosim's floor)", baseline)]:
        best = min(walls)
        print(f"{name:36} {best:6.2f} s  real-time factor {args.duration / best:5.0f}"
              f"  {best / steps * 1e6:6.1f} us/step  (runs: {', '.join(f'{w:.2f}' for w in walls)})")
    print(f"car / floor: {min(car) / min(baseline):.2f}")


if __name__ == "__main__":
    main()
