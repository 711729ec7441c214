#!/usr/bin/env python3
"""Model Exchange derivatives and event indicators of two builds at the same
states: how many differ and by how many ulps.

    .venv/bin/python tools/me_derivative_bits.py BEFORE.fmu AFTER.fmu [--steps N]

Both FMUs (FMI 2.0) are driven in lockstep by one explicit Euler master at
0.1 ms that completes every step and handles the events at step ends: the
states come from the first FMU's derivatives and are set in both, so the
two see the same points and the same delay history, and every difference
is one of arithmetic. Cases: TDVASS with tau = 0 (folded), 1e-8 (folded),
2e-4 and 0.011 s, PVASS, CS, and TDVASS on ISO 8608 class D with the
unilateral tire. Prints, per case, the values that differ, the largest
difference in ulps and relative, and the largest ulps by state index.
"""

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "python"))
from me_master import ModelExchangeMaster  # noqa: E402

CASES = {
    "tdvass tau 0": {"variant": 3, "tau": 0.0},
    "tdvass tau 1e-8": {"variant": 3, "tau": 1e-8},
    "tdvass tau 2e-4": {"variant": 3, "tau": 2e-4},
    "tdvass tau 0.011": {"variant": 3, "tau": 0.011},
    "pvass": {"variant": 2},
    "cs": {"variant": 1},
    "iso D unilateral": {"variant": 3, "road": 2, "road_class": 4, "vehicle_speed": 20.0, "tire_contact": 1,
                         "tau": 0.011},
}


def ulps(a, b):
    ia = np.frombuffer(np.asarray(a, dtype=np.float64).tobytes(), dtype=np.int64)
    ib = np.frombuffer(np.asarray(b, dtype=np.float64).tobytes(), dtype=np.int64)
    return np.abs(ia - ib)


def relative(a, b):
    a, b = np.asarray(a), np.asarray(b)
    scale = np.maximum(np.abs(a), np.abs(b))
    return np.divide(np.abs(a - b), scale, out=np.zeros_like(scale), where=scale > 0)


def compare(before, after, start, steps):
    a, b = ModelExchangeMaster(before, start, name="before"), ModelExchangeMaster(after, start, name="after")
    x, t, h = a.states(), 0.0, 1e-4
    z = a.indicator(t, x)
    b.indicator(t, x)
    counts, worst_ulps, worst_relative, by_state = 0, 0, 0.0, {}
    for k in range(steps):
        da, db = a.derivatives(t, x), b.derivatives(t, x)
        u = ulps(da, db)
        counts += int(np.count_nonzero(u))
        worst_ulps = max(worst_ulps, int(u.max()))
        worst_relative = max(worst_relative, float(relative(da, db).max()))
        for i in np.nonzero(u)[0]:
            by_state[int(i)] = max(by_state.get(int(i), 0), int(u[i]))
        x, t = x + h * da, (k + 1) * h
        za, zb = a.indicator(t, x), b.indicator(t, x)
        counts += int(za != zb)
        worst_ulps = max(worst_ulps, int(ulps([za], [zb])[0]))
        if (z > 0) != (za > 0):
            a.event(t, x)
            b.event(t, x)
            za = a.indicator(t, x)
            b.indicator(t, x)
        z = za
        a.complete()
        b.complete()
    a.free()
    b.free()
    return counts, steps * (len(x) + 1), worst_ulps, worst_relative, by_state


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("--steps", type=int, default=5000)
    args = parser.parse_args()
    for name, start in CASES.items():
        counts, total, worst, rel, by_state = compare(args.before, args.after, start, args.steps)
        print(f"{name:18s} {counts}/{total} values differ; largest {worst} ulps, {rel:.1e} relative; "
              f"by state {by_state}")


if __name__ == "__main__":
    main()
