"""Worst call against the median call of doStep, for real-time masters, and
the same for a fixed-step Model Exchange master.

    .venv/bin/python benches/worst_case.py [--repeats R] [--seconds S] [--fmu FMU ...]

Builds tests/robustness/realtime.c and runs its `worst` mode on the Linux
library of each FMU given (default: target/fmu/tdvass.fmu and
target/fmu/tdvass-fmi3.fmu; an FMU's FMI version is read from its
modelDescription.xml): the same deterministic run R times (default 5), each
call's minimum time over the repetitions, and the largest of these minima
against their median. The cases: the harmonic road, ISO 8608 class E at
30 m/s with the unilateral tire (the most lift-offs) and class D at 20 m/s,
at 1 ms, and the harmonic road and class E at a 0.7 ms master. Several FMUs
are run case by case in turn, so that they share the machine's state.
Each case then runs the harness's `worst-me` mode (the rows marked ME): its
Model Exchange master, Heun's method at the same steps with the events at
step ends and CompletedIntegratorStep after every step, one "call" being
all the FMI calls of one step. Figures in BENCHMARKS.md.
"""

import argparse
import re
import subprocess
import tempfile
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CASES = [
    "harmonic-bilateral-aligned",
    "iso-E-30-unilateral-aligned",
    "iso-D-20-bilateral-aligned",
    "harmonic-bilateral-0.7ms",
    "iso-E-30-unilateral-0.7ms",
]


def unpack(fmu: Path, into: Path) -> tuple[int, str, str]:
    """(FMI version, library path, GUID or instantiation token) of `fmu`."""
    with zipfile.ZipFile(fmu) as z:
        xml = z.read("modelDescription.xml").decode()
        version = 3 if 'fmiVersion="3.0"' in xml else 2
        member = "binaries/x86_64-linux/tdvass.so" if version == 3 else "binaries/linux64/tdvass.so"
        library = into / f"{fmu.stem}-{abs(hash(str(fmu)))}.so"
        library.write_bytes(z.read(member))
    token = re.search(r'(?:guid|instantiationToken)="([^"]+)"', xml).group(1)
    return version, str(library), token


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--fmu", type=Path, action="append")
    args = parser.parse_args()
    fmus = args.fmu or [ROOT / "target/fmu/tdvass.fmu", ROOT / "target/fmu/tdvass-fmi3.fmu"]
    work = Path(tempfile.mkdtemp(prefix="tdvass-worst-"))
    harness = work / "realtime"
    subprocess.run(["gcc", "-O2", "-rdynamic", "-o", str(harness), str(ROOT / "tests/robustness/realtime.c"),
                    "-ldl", "-lm"], check=True)
    libraries = [(fmu, *unpack(fmu, work)) for fmu in fmus]
    print(f"per-call minimum over {args.repeats} runs of {args.seconds:g} s: median, largest (call), largest/median")
    for case in CASES:
        for mode, label in (("worst", "CS"), ("worst-me", "ME")):
            for fmu, version, library, token in libraries:
                out = subprocess.run([str(harness), mode, str(version), library, token, case, str(args.repeats),
                                      str(args.seconds)], capture_output=True, text=True, check=True).stdout
                found = re.search(r"median ([\d.]+) us, largest ([\d.]+) us \(call (\d+)\), largest/median ([\d.]+)",
                                  out)
                median, largest, call, ratio = found.groups()
                print(f"{case:30s} FMI {version} {label}  {median:>8s} us  {largest:>9s} us ({call:>5s})  {ratio:>6s}  "
                      f"{fmu}")


if __name__ == "__main__":
    main()
