"""The tire's contact law, `tire_contact`, in both FMUs (target/fmu/tdvass.fmu
and tdvass-fmi3.fmu) driven from fmpy: the unilateral tire lifts off on a
rough road as the `tdvass` CLI computes it, changes nothing where the wheel
stays on the road, refuses a code that is none and logs each lift-off
under logEvents.

Needs the FMUs (`cargo run --release -p fmu-build`) and the CLI
(`cargo build --release --bin tdvass`; $TDVASS_BIN overrides).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
from pathlib import Path

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave

from fmu_helpers import Slave, fmu_path

STEP = 1e-3  # the DefaultExperiment's stepSize
LIFT_OFF = re.compile(r"lift-off at t = (\S+) s: .*TDD = (\S+) m reaches W/k_t = (\S+) m")


def cli_path() -> Path:
    override = os.environ.get("TDVASS_BIN")
    if override:
        return Path(override)
    return fmu_path().parent.parent / "release" / "tdvass"


@pytest.fixture(scope="session")
def cli() -> Path:
    path = cli_path()
    if not path.is_file():
        pytest.fail(f"{path} not found; build it with `cargo build --release --bin tdvass`")
    return path


class Fmu:
    """One FMU (FMI 2.0 or 3.0), extracted once, with its variables."""

    def __init__(self, path: Path, unzipdir: Path):
        self.path = path
        self.unzipdir = unzipdir
        self.md = read_model_description(str(path))
        self.version = self.md.fmiVersion
        self.variables = {v.name: v for v in self.md.modelVariables}
        real = "Real" if self.version == "2.0" else "Float64"
        self.reals = [v.name for v in self.md.modelVariables if v.causality == "output" and v.type == real]

    def code(self, name: str, item: str) -> int:
        """The code of `item` (a name of the FMI 3.0 Enumeration `name`)."""
        return {i.name: int(i.value) for i in self.variables[name].declaredType.items}[item]


@pytest.fixture(scope="session", params=["2.0", "3.0"], ids=["fmi2", "fmi3"])
def fmu(request, tmp_path_factory) -> Fmu:
    path = fmu_path() if request.param == "2.0" else fmu_path().with_name("tdvass-fmi3.fmu")
    if not path.is_file():
        pytest.fail(f"{path} not found; build it with `cargo run --release -p fmu-build`")
    return Fmu(path, Path(extract(str(path), unzipdir=str(tmp_path_factory.mktemp("fmu")))))


class Instance:
    """An instance of either FMU: integer settings by their codes, the Real
    outputs and `lift_off_count` read after each step, and the log as
    (status, category, message)."""

    def __init__(self, fmu: Fmu, logging: bool = False):
        self.fmu = fmu
        self.vr = {name: v.valueReference for name, v in fmu.variables.items()}
        self.time = 0.0
        if fmu.version == "2.0":
            self.slave = Slave(fmu.unzipdir, fmu.md, logging_on=logging)
            self.c = self.slave.fmu
            self.log = self.slave.log.messages
        else:
            self.log = []

            def log_message(_environment, status, category, message):
                self.log.append((status, category.decode(), message.decode(errors="replace")))

            self.c = FMU3Slave(guid=fmu.md.guid, unzipDirectory=str(fmu.unzipdir),
                               modelIdentifier=fmu.md.coSimulation.modelIdentifier, instanceName="tire")
            self.c.instantiate(loggingOn=logging, logMessage=log_message)

    def set_integers(self, **values):
        for name, value in values.items():
            if self.fmu.version == "2.0":
                self.c.setInteger([self.vr[name]], [value])
            else:
                self.c.setInt64([self.vr[name]], [value])

    def start(self, stop: float, **integers):
        if self.fmu.version == "2.0":
            self.c.setupExperiment(startTime=0.0, stopTime=stop)
            self.c.enterInitializationMode()
        else:
            self.c.enterInitializationMode(startTime=0.0, stopTime=stop)
        self.set_integers(**integers)
        self.c.exitInitializationMode()
        return self

    def read(self) -> tuple[list[float], int]:
        reals = [self.vr[n] for n in self.fmu.reals]
        if self.fmu.version == "2.0":
            return list(self.c.getReal(reals)), self.c.getInteger([self.vr["lift_off_count"]])[0]
        return list(self.c.getFloat64(reals)), self.c.getInt32([self.vr["lift_off_count"]])[0]

    def run(self, stop: float) -> list[tuple[list[float], int]]:
        """The outputs at every STEP up to `stop`."""
        rows = []
        for k in range(1, round(stop / STEP) + 1):
            t = k * STEP
            self.c.doStep(self.time, t - self.time)
            self.time = t
            rows.append(self.read())
        return rows

    def output(self, name: str) -> float:
        reals, _ = self.read()
        return reals[self.fmu.reals.index(name)]

    def free(self):
        self.c.terminate()
        self.c.freeInstance()


def class_d(fmu: Fmu, unilateral: bool) -> dict:
    """ISO 8608 class D (the road's other settings at their start values)."""
    if fmu.version == "2.0":
        return {"road": 2, "road_class": 4, "tire_contact": int(unilateral)}
    return {"road": fmu.code("road", "iso8608"), "road_class": fmu.code("road_class", "D"),
            "tire_contact": fmu.code("tire_contact", "unilateral" if unilateral else "bilateral")}


def test_the_description_declares_both_variables(fmu):
    contact, count = fmu.variables["tire_contact"], fmu.variables["lift_off_count"]
    assert (contact.causality, contact.variability, contact.start) == ("parameter", "fixed", "0")
    assert (count.causality, count.variability) == ("output", "discrete")
    if fmu.version == "2.0":
        assert contact.type == count.type == "Integer"
    else:
        assert contact.type == "Enumeration" and count.type == "Int32"
        assert fmu.code("tire_contact", "bilateral") == 0 and fmu.code("tire_contact", "unilateral") == 1


def test_a_class_d_road_lifts_the_wheel_off_as_the_cli_computes_it(fmu, cli):
    stop = 5.0
    inst = Instance(fmu).start(stop, **class_d(fmu, unilateral=True))
    rows = inst.run(stop)
    counts = [count for _, count in rows]
    flight = inst.output("contact_loss_time")
    inst.free()
    assert counts[-1] > 0
    assert all(a <= b for a, b in zip(counts, counts[1:]))
    ran = subprocess.run([str(cli), "simulate", "--road", "iso8608", "--road-class", "D", "--duration", str(stop),
                          "--tire-contact", "unilateral", "--json"], capture_output=True, text=True, check=True)
    reference = json.loads(ran.stdout)
    assert reference["tire_contact"] == "unilateral"
    assert counts[-1] == reference["lift_off_count"]
    assert flight == pytest.approx(reference["contact_loss_time"], rel=1e-9, abs=0.0)
    # The bilateral tire on the same road: another run.
    bilateral = Instance(fmu).start(stop, **class_d(fmu, unilateral=False))
    bilateral.run(stop)
    assert bilateral.output("contact_loss_time") != flight
    bilateral.free()


def test_without_lift_off_both_tires_give_the_same_run_bit_for_bit(fmu):
    stop = 15.0  # the DefaultExperiment
    contact = {"tire_contact": 1 if fmu.version == "2.0" else fmu.code("tire_contact", "unilateral")}
    runs = []
    for values in ({}, contact):
        inst = Instance(fmu).start(stop, **values)
        runs.append(inst.run(stop))
        inst.free()
    bilateral, unilateral = runs
    assert len(bilateral) == len(unilateral) == 15000
    assert all(count == 0 for _, count in unilateral)
    for k, (a, b) in enumerate(zip(bilateral, unilateral)):
        assert a == b, f"t = {(k + 1) * STEP}: {a} != {b}"


def test_a_code_that_is_none_is_refused_naming_it(fmu):
    inst = Instance(fmu)
    if fmu.version == "2.0":
        inst.c.setupExperiment(startTime=0.0)
        inst.c.enterInitializationMode()
    else:
        inst.c.enterInitializationMode(startTime=0.0)
    with pytest.raises(FMICallException):
        inst.set_integers(tire_contact=2)
    status, _, message = inst.log[-1]
    assert status == 3, inst.log[-1]  # Error
    assert "`tire_contact`" in message and "2" in message, message
    # Nothing changed: the run starts with the bilateral tire.
    inst.c.exitInitializationMode()
    inst.free()


def test_each_lift_off_is_logged_under_log_events(fmu):
    stop = 3.0
    for logging in (True, False):
        inst = Instance(fmu, logging=logging).start(stop, **class_d(fmu, unilateral=True))
        count = inst.run(stop)[-1][1]
        lift_offs = [(c, LIFT_OFF.search(m)) for s, c, m in inst.log if "lift-off at t = " in m]
        warnings = [m for s, _, m in inst.log if "the tire leaves the road" in m]
        inst.free()
        assert count > 0
        assert not warnings, warnings
        if not logging:
            assert lift_offs == []
            continue
        assert len(lift_offs) == count, inst.log[-5:]
        times = []
        for category, found in lift_offs:
            assert category == "logEvents"
            time, tdd, limit = (float(found.group(i)) for i in (1, 2, 3))
            assert tdd == pytest.approx(limit, rel=1e-9)
            times.append(time)
        assert all(0.0 < a < b <= stop for a, b in zip(times, times[1:]))
    # The bilateral tire on the same road warns once and logs no lift-off.
    inst = Instance(fmu, logging=True).start(stop, **class_d(fmu, unilateral=False))
    inst.run(stop)
    assert len([m for s, _, m in inst.log if s == 1 and "the tire leaves the road" in m]) == 1
    assert not [m for _, _, m in inst.log if "lift-off at t = " in m]
    inst.free()
