#!/usr/bin/env python3
"""Bit-identity digests of every output of the FMUs and the command line.

    python tools/output_digests.py --fmu2 target/fmu/tdvass.fmu \
        --fmu3 target/fmu/tdvass-fmi3.fmu --cli target/release/tdvass > digests.txt

(One list of every case, with its inputs beside its name: hence the
length.) It prints one line per case, `<case> <first 16 hex digits of a sha256>`, always
the same cases in the same order, so that the files of two builds (before
and after a refactor) compare with `diff`. A case that fails prints
`<case> ERROR <message>` instead; the script itself does not stop.

What is hashed:
  * FMU runs (FMI 2.0 through fmpy.fmi2.FMU2Slave, FMI 3.0 through
    fmpy.fmi3.FMU3Slave, an explicit master loop): the raw IEEE-754 bits
    (little-endian) of the time and of every Real/Float64 output and every
    integer output (lift_off_count) at every communication point, plus the
    calculated parameters after initialization. Matrix: variant x road x
    tire_contact x step pattern x FMI version, plus cases for the delay
    regimes, negative and changed gains, tolerances, getter patterns,
    output/directional/input derivatives, input extrapolation, FMI 3.0
    intermediate updates and early return. `<case>/log` hashes the FMU's
    log messages of that run.
  * FMU states: the serialized bytes of getFMUstate in the middle and at
    the end of a run (`/state-mid`, `/state-end`), and the outputs of the
    second half rerun after restoring the deserialized middle state
    (`/restore`).
  * The command line: standard output (and the written CSV) of simulate,
    map, optimize, stability, stable and frf (standard error is not hashed:
    its progress lines depend on the wall time).

The FMU cases run in a worker process; a crash there marks that case ERROR
and a new worker goes on with the next one. `--filter REGEX` runs only the
matching cases, `--list` prints the case names.
"""

import argparse
import hashlib
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time as _time

# --------------------------------------------------------------------------
# The case list (fixed order)
# --------------------------------------------------------------------------

T_RUN = 3.0  # simulated seconds of a matrix run

ROADS = [
    # name, start values
    ("harmonic", {"road": 1}),
    ("isoD20", {"road": 2, "road_class": 4, "vehicle_speed": 20.0}),
    ("isoE30", {"road": 2, "road_class": 5, "vehicle_speed": 30.0}),
    ("paper", {"road": 3}),
    ("input", {"road": 0}),
]
PATTERNS = ["a1", "p07", "var"]  # aligned 1 ms, 0.7 ms, varying 0.1..1.9 ms
ISO_E30 = {"road": 2, "road_class": 5, "vehicle_speed": 30.0}
ISO_D20 = {"road": 2, "road_class": 4, "vehicle_speed": 20.0}


def fmu_cases():
    """Every FMU case: dicts with name, fmi, params, pattern and options."""
    cases = []
    for fmi in (2, 3):
        for variant in (1, 2, 3):
            for road_name, road in ROADS:
                for tc in (0, 1):
                    for pattern in PATTERNS:
                        params = dict(road, variant=variant, tire_contact=tc)
                        cases.append(dict(
                            name=f"fmi{fmi}/v{variant}/{road_name}/tc{tc}/{pattern}",
                            fmi=fmi, params=params, pattern=pattern))
        extra = []

        def add(name, params, pattern, **options):
            extra.append(dict(name=f"fmi{fmi}/x/{name}", fmi=fmi, params=params,
                              pattern=pattern, **options))

        v3e = dict(ISO_E30, variant=3, tire_contact=1)
        # the delay regimes: many internal steps, none, inside one step
        add("tau0.011/isoE30/tc1/a1", dict(v3e, tau=0.011), "a1")
        add("tau0.011/isoE30/tc1/var", dict(v3e, tau=0.011), "var")
        add("tau0.011/harmonic/tc0/p07", dict(variant=3, road=1, tau=0.011), "p07")
        add("tau0/isoE30/tc1/a1", dict(v3e, tau=0.0), "a1")
        add("tau0/isoE30/tc1/p07", dict(v3e, tau=0.0), "p07")
        add("tau5e-4/isoE30/tc1/var", dict(v3e, tau=5e-4), "var")
        add("tau0.011/paper/tc1/a1", dict(variant=3, road=3, tire_contact=1, tau=0.011), "a1")
        add("tau0.0105/isoD20/tc1/p07", dict(ISO_D20, variant=3, tire_contact=1, tau=0.0105), "p07")
        # negative gains
        add("g-20000-tau0.011/isoD20/tc0/var", dict(ISO_D20, variant=3, g=-20000.0, tau=0.011), "var")
        add("g-5000/harmonic/tc1/p07", dict(variant=3, road=1, tire_contact=1, g=-5000.0), "p07")
        add("g-150000/isoE30/tc1/a1", dict(v3e, g=-150000.0), "a1")
        # the tunable gain changed in the middle of the run
        add("gchange/isoE30/tc1/p07", v3e, "p07", g_change=(1.0, -3000.0))
        add("gchange-tau0.011/input/tc0/var", dict(variant=3, road=0, tau=0.011), "var",
            g_change=(0.9, 12000.0))
        # unstable (g, tau): the warning at exitInitializationMode
        add("unstable-g50000-tau0.07/harmonic/tc0/a1", dict(variant=3, road=1, g=50000.0, tau=0.07), "a1")
        # other tolerances and a bounded internal step
        add("tol1e-9/isoE30/tc1/p07", v3e, "p07", tolerance=1e-9, t_end=0.6)
        add("tol1e-3/harmonic/tc0/var", dict(variant=3, road=1), "var", tolerance=1e-3)
        add("tol1e-4/paper/tc1/p07", dict(variant=2, road=3, tire_contact=1), "p07", tolerance=1e-4)
        add("maxstep2.5e-4/isoE30/tc1/p07", dict(v3e, max_internal_step=2.5e-4), "p07")
        # initial state away from rest (history before the start)
        add("start-state-tau0.011/harmonic/tc1/var",
            dict(variant=3, road=1, tire_contact=1, tau=0.011, x_s_start=0.01,
                 v_s_start=-0.05, x_h_start=0.002, v_h_start=0.03, x_t_start=0.005,
                 v_t_start=0.1), "var")
        add("seed7/isoD20/tc1/p07", dict(ISO_D20, variant=1, tire_contact=1, road_seed=7), "p07")
        add("weights/paper/tc0/var", dict(variant=3, road=3, w_ba=1.0, w_sdd=2.0, w_tdd=3.0), "var")
        # getter patterns: the FMU computes only the kind of output asked for
        add("getsplit/isoE30/tc1/p07", v3e, "p07", getter="split")
        add("getsplit/input/tc1/var", dict(variant=2, road=0, tire_contact=1), "var", getter="split")
        add("getsingle/harmonic/tc0/var", dict(variant=3, road=1, tau=0.011), "var",
            getter="single", t_end=0.5)
        # exact derivatives
        add("outder/isoE30/tc1/var", v3e, "var", output_derivatives=True)
        add("outder/input/tc0/p07", dict(variant=3, road=0), "p07", output_derivatives=True)
        add("dirder/isoD20/tc1/p07", dict(ISO_D20, variant=3, tire_contact=1), "p07",
            directional_derivatives=True)
        # a road fed through x_g, extrapolated by the FMU or with derivatives
        add("extrap1/input/tc0/p07", dict(variant=3, road=0, input_extrapolation=1), "p07")
        add("extrap2/input/tc1/var", dict(variant=3, road=0, tire_contact=1, input_extrapolation=2), "var")
        if fmi == 2:
            add("inputder/input/tc0/var", dict(variant=3, road=0), "var", input_derivatives=True)
            add("inputder-extrap2/input/tc1/p07",
                dict(variant=3, road=0, tire_contact=1, input_extrapolation=2), "p07",
                input_derivatives=True)
        # lift-offs logged under logEvents
        add("logevents/isoE30/tc1/var", v3e, "var", log_categories=["logEvents"])
        add("logevents/isoE30/tc0/p07", dict(ISO_E30, variant=2), "p07", log_categories=["logEvents"])
        # coarse communication steps
        add("coarse/isoE30/tc1/c10", v3e, "c10")
        add("coarse-tau0.011/isoD20/tc1/c7.3", dict(ISO_D20, variant=3, tire_contact=1, tau=0.011),
            "c7.3")
        add("coarse/input/tc0/c10", dict(variant=3, road=0, input_extrapolation=2), "c10")
        add("coarse/paper/tc1/c7.3", dict(variant=1, road=3, tire_contact=1), "c7.3")
        # a run started again after fmiReset
        add("reset/isoE30/tc1/p07", dict(v3e, tau=0.011), "p07", reset=True)
        # FMU states
        add("state/isoE30/tc1/p07", dict(v3e, tau=0.011), "p07", states=True)
        add("state/harmonic/tc0/a1", dict(variant=2, road=1), "a1", states=True)
        add("state/input/tc1/var", dict(variant=3, road=0, tire_contact=1, input_extrapolation=2),
            "var", states=True)
        add("state/paper/tc1/var", dict(variant=1, road=3, tire_contact=1), "var", states=True)
        if fmi == 3:
            add("roots5/isoD20/tc0/p07", dict(ISO_D20, variant=3, root_count=5, g=-20000.0,
                                              tau=0.011), "p07")
            add("intermediate/isoE30/tc1/p07", v3e, "p07", intermediate="read", t_end=1.0)
            add("intermediate-every/input/tc0/var", dict(variant=3, road=0), "var",
                intermediate="read", t_end=1.0)
            add("intermediate-interval/isoE30/tc1/var", dict(v3e, intermediate_update_interval=3e-4),
                "var", intermediate="read", t_end=1.0)
            add("intermediate/isoE30/tc1/c10", v3e, "c10", intermediate="read")
            add("intermediate/input/tc1/c7.3", dict(variant=2, road=0, tire_contact=1), "c7.3",
                intermediate="read")
            add("earlyreturn/isoE30/tc1/c10", dict(v3e, tau=0.011), "c10", intermediate="early")
            add("earlyreturn/input/tc0/c7.3", dict(variant=3, road=0, input_extrapolation=1),
                "c7.3", intermediate="early")
        cases.extend(extra)
    return cases


def case_lines(case):
    """The digest lines a case prints, in order."""
    lines = [case["name"]]
    if case.get("states"):
        lines += [case["name"] + "/state-mid", case["name"] + "/state-end",
                  case["name"] + "/restore"]
    lines.append(case["name"] + "/log")
    return lines


def cli_cases():
    """(name, argv, extra files to hash) of the command-line cases."""
    iso = ["--road", "iso8608", "--road-class", "E", "--vehicle-speed", "30",
           "--tire-contact", "unilateral", "--duration", "10"]
    cases = []
    for tau in ("0", "2e-4", "0.011"):
        cases.append((f"cli/simulate/tau{tau}/isoE30/unilateral/json",
                      ["simulate", "--variant", "tdvass", "--tau", tau] + iso + ["--json"], []))
    cases.append(("cli/simulate/tau0.011/isoE30/unilateral/csv",
                  ["simulate", "--variant", "tdvass", "--tau", "0.011"] + iso +
                  ["--json", "--output", "run.csv"], ["run.csv"]))
    cases.append(("cli/simulate/tau2e-4/isoE30/unilateral/csv-0.7ms",
                  ["simulate", "--variant", "tdvass", "--tau", "2e-4"] + iso +
                  ["--output", "run07.csv", "--output-interval", "7e-4"], ["run07.csv"]))
    cases.append(("cli/simulate/g-20000-tau0.011/isoD20/bilateral/json",
                  ["simulate", "--variant", "tdvass", "--g", "-20000", "--tau", "0.011",
                   "--road", "iso", "--road-class", "D", "--vehicle-speed", "20",
                   "--duration", "10", "--json"], []))
    cases.append(("cli/simulate/cs/isoD20/bilateral/table",
                  ["simulate", "--variant", "cs", "--road", "iso8608", "--road-class", "D",
                   "--vehicle-speed", "20", "--duration", "10"], []))
    cases.append(("cli/simulate/pvass/paper/unilateral/json",
                  ["simulate", "--variant", "pvass", "--road", "paper", "--road-seed", "3",
                   "--tire-contact", "unilateral", "--duration", "10", "--json"], []))
    cases.append(("cli/simulate/tdvass/harmonic/json-15s",
                  ["simulate", "--variant", "tdvass", "--road", "harmonic", "--json"], []))
    cases.append(("cli/simulate/tdvass/harmonic/tol1e-9/json",
                  ["simulate", "--variant", "tdvass", "--road", "harmonic", "--tolerance", "1e-9",
                   "--duration", "2", "--json"], []))
    cases.append(("cli/simulate/tdvass/file-road/unilateral/json",
                  ["simulate", "--variant", "tdvass", "--road", "file:profile.csv",
                   "--tire-contact", "unilateral", "--duration", "3", "--json"], []))
    cases.append(("cli/map/csv",
                  ["map", "--g-min", "-200000", "--g-max", "200000", "--g-points", "41",
                   "--tau-max", "0.5", "--tau-points", "41"], []))
    cases.append(("cli/map/json-file",
                  ["map", "--g-min", "-100000", "--g-max", "100000", "--g-points", "31",
                   "--tau-max", "0.1", "--tau-points", "31", "--output", "map.csv", "--json"],
                  ["map.csv"]))
    cases.append(("cli/optimize/controller/isoE30/unilateral",
                  ["optimize", "controller", "--road", "iso8608", "--road-class", "E",
                   "--vehicle-speed", "30", "--tire-contact", "unilateral", "--particles", "6",
                   "--iterations", "4", "--seed", "1", "--duration", "2", "--json"], []))
    cases.append(("cli/optimize/controller/harmonic",
                  ["optimize", "controller", "--road", "harmonic", "--particles", "6",
                   "--iterations", "4", "--seed", "2", "--duration", "2", "--json"], []))
    cases.append(("cli/optimize/absorber/comfort/isoD20",
                  ["optimize", "absorber", "--objective", "comfort", "--road", "iso8608",
                   "--road-class", "D", "--vehicle-speed", "20", "--particles", "5",
                   "--iterations", "3", "--seed", "1", "--duration", "2", "--json"], []))
    cases.append(("cli/stability/g50000/json",
                  ["stability", "--g", "50000", "--tau-max", "0.5", "--json"], []))
    cases.append(("cli/stability/g-250000/table",
                  ["stability", "--g", "-250000", "--tau-max", "0.1"], []))
    cases.append(("cli/stable/g40000-tau0.03/json",
                  ["stable", "--g", "40000", "--tau", "0.03", "--json"], []))
    cases.append(("cli/frf/tdvass/csv",
                  ["frf", "--variant", "tdvass", "--g", "2528", "--tau", "1.28e-4",
                   "--f-min", "0.1", "--f-max", "30", "--points", "200"], []))
    cases.append(("cli/frf/cs/json", ["frf", "--variant", "cs", "--json"], []))
    cases.append(("cli/frf/tdvass-tau0.011/json",
                  ["frf", "--variant", "tdvass", "--tau", "0.011", "--json"], []))
    return cases


ROAD_PROFILE = "t,x_g\n0,0\n0.5,0.02\n1,-0.03\n1.2,0.05\n2,0\n"

# --------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------


def short(h):
    return h.hexdigest()[:16]


def pack_f64(values):
    return struct.pack("<%dd" % len(values), *values)


def pack_i64(values):
    return struct.pack("<%dq" % len(values), *values)


def step_sequence(pattern, t_end):
    """The communication steps of a pattern: a list of (t, h)."""
    steps = []
    if pattern == "a1":
        n = int(round(t_end / 1e-3))
        # communication points k * 1 ms, as a master that counts steps
        for k in range(n):
            steps.append((k * 1e-3, 1e-3))
    elif pattern == "p07":
        n = int(round(t_end / 7e-4))
        t = 0.0
        for _ in range(n):
            steps.append((t, 7e-4))
            t += 7e-4
    elif pattern in ("c10", "c7.3"):
        # coarse steps over many internal steps: 10 ms counted, 7.3 ms summed
        h = 1e-2 if pattern == "c10" else 7.3e-3
        n = int(round(t_end / h))
        t = 0.0
        for k in range(n):
            steps.append((k * h if pattern == "c10" else t, h))
            t += h
    elif pattern == "var":
        state = 20240601  # a fixed LCG (Numerical Recipes constants)
        t = 0.0
        while t < t_end:
            state = (1664525 * state + 1013904223) % (1 << 32)
            h = 1e-4 + 1.8e-3 * (state / float(1 << 32))
            steps.append((t, h))
            t += h
    else:
        raise ValueError("pattern " + pattern)
    return steps


def road_input(t):
    return 0.05 * math.sin(5.0 * t)


def road_input_slope(t):
    return 0.25 * math.cos(5.0 * t)


# --------------------------------------------------------------------------
# One FMU case
# --------------------------------------------------------------------------


class Model:
    """A model description and the unzipped FMU."""

    def __init__(self, fmi, path, tmp):
        from fmpy import read_model_description, extract
        self.fmi = fmi
        self.md = read_model_description(path)
        self.dir = extract(path, unzipdir=os.path.join(tmp, "fmu%d" % fmi))
        self.vars = {v.name: v for v in self.md.modelVariables}
        reals = ("Real", "Float64")
        ints = ("Integer", "Enumeration", "Int32", "Int64", "UInt64", "Int8", "Int16",
                "UInt8", "UInt16", "UInt32")
        self.real_out = [v for v in self.md.modelVariables
                         if v.causality == "output" and v.type in reals]
        self.int_out = [v for v in self.md.modelVariables
                        if v.causality == "output" and v.type in ints]
        self.calculated = [v for v in self.md.modelVariables
                           if v.causality == "calculatedParameter"]
        if not self.real_out or not self.int_out:
            raise RuntimeError("no Real or integer outputs in the model description")
        self.real_vrs = [v.valueReference for v in self.real_out]
        self.int_vrs = [v.valueReference for v in self.int_out]
        names = [v.name for v in self.real_out]
        instantaneous = ["x_s", "v_s", "x_h", "v_h", "x_t", "v_t", "body_acceleration",
                         "suspension_deflection", "tire_deflection", "road_displacement",
                         "control_force", "dynamic_tire_load"]
        averages = ["rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection",
                    "objective", "rms_dynamic_tire_load_ratio"]
        rest = [n for n in names if n not in instantaneous and n not in averages]
        self.split_groups = [[self.vars[n].valueReference for n in group if n in self.vars]
                             for group in (instantaneous, averages, rest, averages[::-1] + instantaneous)]
        # partials of the outputs with respect to x_g and the states
        self.dir_knowns = [self.vars[n].valueReference for n in ("x_g", "x_s", "v_s", "x_h", "v_h", "x_t", "v_t")]
        self.dir_unknowns = [self.vars[n].valueReference for n in
                             ("x_s", "v_s", "x_h", "v_h", "x_t", "v_t", "body_acceleration",
                              "suspension_deflection", "tire_deflection", "control_force",
                              "dynamic_tire_load")]


class Run:
    """One instance of an FMU driven by an explicit master loop."""

    def __init__(self, model, case):
        self.model = model
        self.case = case
        self.fmi = model.fmi
        self.logs = hashlib.sha256()
        self.fmu = None

    # --- logging --------------------------------------------------------
    def _log(self, status, category, message):
        # the unzipped FMU lies in a new temporary directory in every run
        message = (message or b"").replace(os.fsencode(self.model.dir), b"<unzipdir>")
        self.logs.update(b"%d\0%s\0%s\n" % (status, category or b"", message))

    def _log2(self, env, instance, status, category, message):
        self._log(status, category, message)

    def _log3(self, env, status, category, message):
        self._log(status, category, message)

    # --- typed access ---------------------------------------------------
    def set_value(self, name, value):
        v = self.model.vars[name]
        vr = [v.valueReference]
        f = self.fmu
        if self.fmi == 2:
            if v.type == "Real":
                f.setReal(vr, [float(value)])
            elif v.type == "Boolean":
                f.setBoolean(vr, [bool(value)])
            else:
                f.setInteger(vr, [int(value)])
        else:
            t = v.type
            if t == "Float64":
                f.setFloat64(vr, [float(value)])
            elif t in ("Enumeration", "Int64"):
                f.setInt64(vr, [int(value)])
            elif t == "Int32":
                f.setInt32(vr, [int(value)])
            elif t == "UInt64":
                f.setUInt64(vr, [int(value)])
            elif t == "Boolean":
                f.setBoolean(vr, [bool(value)])
            else:
                raise RuntimeError("cannot set %s of type %s" % (name, t))

    def get_reals(self, vrs):
        if self.fmi == 2:
            return self.fmu.getReal(vrs)
        return self.fmu.getFloat64(vrs)

    def get_ints(self):
        f = self.fmu
        values = []
        for v in self.model.int_out:
            vr = [v.valueReference]
            if self.fmi == 2:
                values += f.getInteger(vr)
            elif v.type == "Int32":
                values += f.getInt32(vr)
            elif v.type == "UInt64":
                values += f.getUInt64(vr)
            else:
                values += f.getInt64(vr)
        return values

    def get_calculated(self):
        """The calculated parameters, as float64 values."""
        f = self.fmu
        values = []
        for v in self.model.calculated:
            vr = [v.valueReference]
            if v.type == "Boolean":
                values += [float(x) for x in f.getBoolean(vr)]
            elif self.fmi == 2:
                values += f.getReal(vr) if v.type == "Real" else [float(x) for x in f.getInteger(vr)]
            elif v.type == "Float64":
                n = 1
                if v.dimensions:
                    n = 1
                    for d in v.dimensions:
                        if d.start is not None:
                            n *= int(d.start)
                        else:
                            ref = d.valueReference
                            n *= int(f.getUInt64([ref])[0])
                values += f.getFloat64(vr, nValues=n)
            else:
                values += [float(x) for x in self.get_ints_of(v)]
        return values

    def get_ints_of(self, v):
        vr = [v.valueReference]
        if v.type == "Int32":
            return self.fmu.getInt32(vr)
        if v.type == "UInt64":
            return self.fmu.getUInt64(vr)
        return self.fmu.getInt64(vr)

    # --- the run --------------------------------------------------------
    def hash_point(self, h, t):
        m = self.model
        h.update(pack_f64([t]))
        getter = self.case.get("getter", "all")
        if getter == "all":
            h.update(pack_f64(self.get_reals(m.real_vrs)))
        elif getter == "split":
            for group in m.split_groups:
                h.update(pack_f64(self.get_reals(group)))
        else:  # one variable per call, in reverse order
            for vr in reversed(m.real_vrs):
                h.update(pack_f64(self.get_reals([vr])))
        h.update(pack_i64(self.get_ints()))
        if self.case.get("output_derivatives"):
            vrs = m.real_vrs
            if self.fmi == 2:
                d = self.fmu.getRealOutputDerivatives(vrs, [1] * len(vrs))
            else:
                d = self.fmu.getOutputDerivatives(vrs, [1] * len(vrs))
            h.update(b"D" + pack_f64(d))

    def directional(self, h):
        m = self.model
        for i in range(len(m.dir_knowns)):
            seed = [0.0] * len(m.dir_knowns)
            seed[i] = 1.0
            d = self.fmu.getDirectionalDerivative(m.dir_unknowns, m.dir_knowns, seed)
            h.update(b"J" + pack_f64(d))

    def instantiate(self):
        from fmpy.fmi2 import (FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE,
                               fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE)
        from fmpy.fmi3 import FMU3Slave
        from fmpy import calloc, free
        from ctypes import byref
        md, case = self.model.md, self.case
        kwargs = dict(guid=md.guid, unzipDirectory=self.model.dir,
                      modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="digest")
        if self.fmi == 2:
            self.fmu = FMU2Slave(**kwargs)
            cb = fmi2CallbackFunctions()
            cb.logger = fmi2CallbackLoggerTYPE(self._log2)
            cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
            from fmpy.logging import addLoggerProxy
            addLoggerProxy(byref(cb))
            self.callbacks = cb
            self.fmu.instantiate(callbacks=cb, loggingOn=bool(case.get("log_categories")))
        else:
            self.fmu = FMU3Slave(**kwargs)
            intermediate = case.get("intermediate")
            self.fmu.instantiate(loggingOn=bool(case.get("log_categories")),
                                 earlyReturnAllowed=(intermediate == "early"),
                                 logMessage=self._log3,
                                 intermediateUpdate=self._intermediate if intermediate else None)
        if case.get("log_categories"):
            self.fmu.setDebugLogging(True, case["log_categories"])
        self.setup()

    def setup(self):
        """Tolerance, start values, initialization."""
        case = self.case
        tol = case.get("tolerance", 1e-6)
        params = dict(case["params"])
        if self.fmi == 2:
            params.pop("root_count", None)
            params.pop("intermediate_update_interval", None)
            self.fmu.setupExperiment(tolerance=tol, startTime=0.0)
        for name in sorted(params):
            self.set_value(name, params[name])
        if self.fmi == 2:
            self.fmu.enterInitializationMode()
        else:
            self.fmu.enterInitializationMode(tolerance=tol, startTime=0.0)
        self.uses_input = params.get("road") == 0
        if self.uses_input:
            self.set_input(0.0)
        self.fmu.exitInitializationMode()

    def set_input(self, t):
        self.set_value("x_g", road_input(t))
        if self.case.get("input_derivatives"):
            self.fmu.setRealInputDerivatives([self.model.vars["x_g"].valueReference], [1],
                                             [road_input_slope(t)])

    def _intermediate(self, env, time, set_requested, get_allowed, step_finished,
                      can_return_early, early_requested, early_time):
        try:
            self.n_intermediate += 1
            h = self.current_hash
            h.update(b"I" + pack_f64([time]) + bytes([bool(set_requested), bool(get_allowed),
                                                      bool(step_finished), bool(can_return_early)]))
            if get_allowed:
                h.update(pack_f64(self.fmu.getFloat64(self.model.real_vrs)))
            if set_requested and self.uses_input:
                self.fmu.setFloat64([self.model.vars["x_g"].valueReference], [road_input(time)])
            early_requested[0] = False
            if (self.case.get("intermediate") == "early" and can_return_early
                    and time < self.step_end - 1e-9):
                self.n_eligible += 1
                if self.n_eligible % 3 == 0:
                    early_requested[0] = True
                    early_time[0] = time
        except Exception as e:  # never raise through the FMU
            self.callback_error = repr(e)

    def run(self):
        """The digests of the case's lines."""
        case = self.case
        out = {}
        self.n_intermediate = 0
        self.n_eligible = 0
        self.step_end = 0.0
        self.callback_error = None
        self.g_done = False
        h = hashlib.sha256()
        self.current_hash = h
        self.instantiate()
        try:
            if case.get("reset"):
                # half a second of the case, then fmiReset and the whole run
                for t, step in step_sequence("var", 0.5):
                    self.do_step(t, step, h)
                h.update(pack_f64(self.get_reals(self.model.real_vrs)))
                self.fmu.reset()
                self.setup()
            h.update(b"C" + pack_f64(self.get_calculated()))
            t_end = case.get("t_end", T_RUN)
            steps = step_sequence(case["pattern"], t_end)
            self.hash_point(h, 0.0)
            mid = len(steps) // 2
            states = {}
            second_half = None
            g_change = case.get("g_change")
            k = 0
            t = 0.0
            while k < len(steps):
                if case.get("states") and k == mid:
                    states["mid"] = self.take_state()
                    second_half = hashlib.sha256()
                t, step = steps[k]
                if self.early_t is not None:
                    # continue from the early return: the rest of the step
                    t, step = self.early_t, steps[k][0] + steps[k][1] - self.early_t
                    self.early_t = None
                if g_change and t >= g_change[0] and not self.g_done:
                    # the tunable gain, set before the first step from g_change[0] on
                    self.set_value("g", g_change[1])
                    self.g_done = True
                    h.update(b"G")
                if self.uses_input:
                    self.set_input(t)
                ok, t_now = self.do_step(t, step, h)
                if self.callback_error:
                    raise RuntimeError("intermediate update: " + self.callback_error)
                self.hash_point(h, t_now)
                if second_half is not None:
                    self.hash_point(second_half, t_now)
                if case.get("directional_derivatives") and k % 100 == 0:
                    self.directional(h)
                if not ok:
                    h.update(b"DISCARD")
                    break
                if self.early_t is None:
                    k += 1
            out[case["name"]] = short(h)
            if case.get("states"):
                states["end"] = self.take_state()
                out[case["name"] + "/state-mid"] = short(hashlib.sha256(states["mid"]))
                out[case["name"] + "/state-end"] = short(hashlib.sha256(states["end"]))
                out[case["name"] + "/restore"] = self.restore_and_rerun(states["mid"], steps, mid,
                                                                        second_half)
        finally:
            try:
                self.fmu.terminate()
            except Exception:
                pass
            try:
                self.fmu.freeInstance()
            except Exception:
                pass
        out[case["name"] + "/log"] = short(self.logs)
        return out

    early_t = None

    def do_step(self, t, step, h):
        """doStep; (True, new time) or (False, time) after a Discard."""
        from fmpy.fmi1 import FMICallException
        try:
            if self.fmi == 2:
                self.fmu.doStep(t, step)
                return True, t + step
            self.step_end = t + step
            event, terminate, early, last = self.fmu.doStep(t, step)
            h.update(bytes([bool(event), bool(terminate), bool(early)]))
            if early:
                h.update(b"E" + pack_f64([last]))
                self.early_t = last
                return True, last
            return True, t + step
        except FMICallException as e:
            if e.status != 2:
                raise
            h.update(b"discard" + pack_f64([t]))
            return False, t

    def take_state(self):
        f = self.fmu
        state = f.getFMUstate() if self.fmi == 2 else f.getFMUState()
        try:
            data = f.serializeFMUstate(state) if self.fmi == 2 else f.serializeFMUState(state)
        finally:
            if self.fmi == 2:
                f.freeFMUstate(state)
            else:
                f.freeFMUState(state)
        return bytes(data)

    def restore_and_rerun(self, data, steps, mid, reference):
        """Deserialize the middle state, rerun the second half; its digest
        (`MISMATCH` appended when it differs from the first pass)."""
        f = self.fmu
        if self.fmi == 2:
            state = f.deSerializeFMUstate(data)
            f.setFMUstate(state)
            f.freeFMUstate(state)
        else:
            state = f.deserializeFMUState(data)
            f.setFMUState(state)
            f.freeFMUState(state)
        h = hashlib.sha256()
        g_change = self.case.get("g_change")
        for t, step in steps[mid:]:
            if g_change and t >= g_change[0] and not self.g_done:
                self.set_value("g", g_change[1])
                self.g_done = True
            if self.uses_input:
                self.set_input(t)
            ok, t_now = self.do_step(t, step, hashlib.sha256())
            self.hash_point(h, t_now)
            if not ok:
                break
        digest = short(h)
        if reference is not None and short(reference) != digest:
            digest += " MISMATCH"
        return digest


# --------------------------------------------------------------------------
# The worker (FMU cases) and the command-line cases
# --------------------------------------------------------------------------


def worker(args):
    cases = selected(fmu_cases(), args.filter)
    tmp = tempfile.mkdtemp(prefix="digests-")
    models = {}
    try:
        for case in cases[args.start:]:
            lines = case_lines(case)
            try:
                fmi = case["fmi"]
                if fmi not in models:
                    models[fmi] = Model(fmi, args.fmu2 if fmi == 2 else args.fmu3, tmp)
                out = Run(models[fmi], case).run()
                for line in lines:
                    print(line, out.get(line, "ERROR no digest"), flush=True)
            except Exception as e:
                msg = error_text(e)
                for line in lines:
                    print(line, "ERROR " + msg, flush=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def error_text(e):
    text = ("%s: %s" % (type(e).__name__, e)).replace("\n", " ")
    return text[:200]


def selected(cases, pattern, key=lambda c: c["name"]):
    if not pattern:
        return cases
    r = re.compile(pattern)
    return [c for c in cases if r.search(key(c))]


def run_fmu_cases(args):
    """Runs the FMU cases in worker processes; a worker that dies marks its
    case ERROR and a new one continues with the next."""
    cases = selected(fmu_cases(), args.filter)
    start = 0
    while start < len(cases):
        cmd = [sys.executable, os.path.abspath(__file__), "--worker", "--start", str(start),
               "--fmu2", args.fmu2, "--fmu3", args.fmu3, "--cli", args.cli]
        if args.filter:
            cmd += ["--filter", args.filter]
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True, bufsize=1)
        case_index, line_index = start, 0
        expected = case_lines(cases[case_index]) if case_index < len(cases) else []
        for raw in proc.stdout:
            name, _, digest = raw.rstrip("\n").partition(" ")
            if case_index >= len(cases) or name != expected[line_index]:
                continue  # not a digest line (something printed by the FMU)
            print(name, digest, flush=True)
            line_index += 1
            if line_index == len(expected):
                case_index += 1
                line_index = 0
                expected = case_lines(cases[case_index]) if case_index < len(cases) else []
        err = proc.stderr.read()
        code = proc.wait()
        if case_index >= len(cases):
            break
        last = err.strip().splitlines()[-1] if err.strip() else ""
        msg = "ERROR worker died (exit %s) %s" % (code, last[:150])
        for name in expected[line_index:]:
            print(name, msg, flush=True)
        start = case_index + 1


def run_cli_cases(args):
    cli = os.path.abspath(args.cli)
    for name, argv, files in selected(cli_cases(), args.filter, key=lambda c: c[0]):
        tmp = tempfile.mkdtemp(prefix="digests-cli-")
        try:
            with open(os.path.join(tmp, "profile.csv"), "w") as f:
                f.write(ROAD_PROFILE)
            proc = subprocess.run([cli] + argv, cwd=tmp, stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, timeout=300,
                                  env=dict(os.environ, NO_COLOR="1"))
            if proc.returncode != 0:
                err = proc.stderr.decode("utf-8", "replace").strip().splitlines()
                raise RuntimeError("exit %d %s" % (proc.returncode, err[-1] if err else ""))
            digests = [short(hashlib.sha256(proc.stdout))]
            for file in files:
                with open(os.path.join(tmp, file), "rb") as f:
                    digests.append(short(hashlib.sha256(f.read())))
        except Exception as e:
            digests = ["ERROR " + error_text(e)] * (1 + len(files))
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        for line, digest in zip(cli_lines(name, files), digests):
            print(line, digest, flush=True)


def cli_lines(name, files):
    """The digest lines of a command-line case: its standard output, then
    each file it writes."""
    return [name] + [name + "/" + file for file in files]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--fmu2", required=False, help="the FMI 2.0 FMU (tdvass.fmu)")
    p.add_argument("--fmu3", required=False, help="the FMI 3.0 FMU (tdvass-fmi3.fmu)")
    p.add_argument("--cli", required=False, help="the tdvass executable")
    p.add_argument("--filter", help="only the cases whose name matches this regular expression")
    p.add_argument("--list", action="store_true", help="print the case names and exit")
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--start", type=int, default=0, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.list:
        for case in selected(fmu_cases(), args.filter):
            for line in case_lines(case):
                print(line)
        for name, _, files in selected(cli_cases(), args.filter, key=lambda c: c[0]):
            for line in cli_lines(name, files):
                print(line)
        return
    if not (args.fmu2 and args.fmu3 and args.cli):
        p.error("--fmu2, --fmu3 and --cli are required")
    args.fmu2, args.fmu3 = os.path.abspath(args.fmu2), os.path.abspath(args.fmu3)
    if args.worker:
        worker(args)
        return
    started = _time.monotonic()
    run_fmu_cases(args)
    run_cli_cases(args)
    print("run time %.0f s" % (_time.monotonic() - started), file=sys.stderr)


if __name__ == "__main__":
    main()
