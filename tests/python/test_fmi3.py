"""The FMI 3.0 FMU (target/fmu/tdvass-fmi3.fmu) driven from fmpy, against
the paper and against the FMI 2.0 FMU built from the same core."""

import subprocess
import sys
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave, fmi3IntermediateUpdateCallback
from fmpy.validation import validate_fmu

from fmu_helpers import OUTPUTS, RMS, fmu_path
from test_fmu import TABLE2, agrees_to_printed_digit

HERE = Path(__file__).resolve().parent


def fmi3_path() -> Path:
    """target/fmu/tdvass-fmi3.fmu, next to the FMI 2.0 FMU."""
    return fmu_path().with_name("tdvass-fmi3.fmu")


@pytest.fixture(scope="session")
def fmi3_file() -> Path:
    path = fmi3_path()
    if not path.is_file():
        pytest.fail(f"{path} not found; build it with `cargo run --release -p fmu-build`")
    return path


@pytest.fixture(scope="session")
def md3(fmi3_file):
    return read_model_description(str(fmi3_file))


@pytest.fixture(scope="session")
def unzip3(fmi3_file, tmp_path_factory):
    return extract(str(fmi3_file), unzipdir=str(tmp_path_factory.mktemp("fmi3")))


def enumeration_value(md, variable, item):
    """The code of `item` of the Enumeration `variable`, looked up by name
    in the model description's type definitions."""
    var = next(v for v in md.modelVariables if v.name == variable)
    items = {i.name: int(i.value) for i in var.declaredType.items}
    return items[item]


def test_validate_fmu_reports_no_problems(fmi3_file):
    assert validate_fmu(str(fmi3_file)) == []


def test_description_declares_fmi3_cosimulation(md3):
    assert md3.fmiVersion == "3.0"
    assert md3.coSimulation.modelIdentifier == "tdvass"
    types = {v.name: v.type for v in md3.modelVariables}
    assert types["variant"] == types["road"] == types["road_class"] == "Enumeration"
    assert types["road_seed"] == "Int32"
    assert types["stable"] == "Boolean"
    assert types["x_s"] == "Float64"


@pytest.mark.parametrize("item, row", [("CS", 1), ("PVASS", 2), ("TDVASS", 3)])
def test_simulate_fmu_reproduces_table2(fmi3_file, md3, item, row):
    result = fmpy.simulate_fmu(
        str(fmi3_file),
        fmi_type="CoSimulation",
        start_values={"variant": enumeration_value(md3, "variant", item)},
        output=RMS,
    )
    last = result[-1]
    assert last["time"] == pytest.approx(15.0)
    ours = (last["rms_body_acceleration"], last["rms_suspension_deflection"], 1e3 * last["rms_tire_deflection"])
    for value, paper in zip(ours, TABLE2[row]):
        assert agrees_to_printed_digit(value, paper), (ours, TABLE2[row])


@pytest.mark.parametrize(
    "fmi2_values, fmi3_items",
    [
        ({}, {}),
        ({"variant": 1, "road": 2, "road_class": 3, "road_seed": 7},
         {"variant": "CS", "road": "iso8608", "road_class": "C"}),
    ],
    ids=["default experiment", "CS ISO 8608 C seed 7"],
)
def test_every_output_equals_the_fmi2_fmu(fmi3_file, md3, fmi2_values, fmi3_items):
    start3 = {name: enumeration_value(md3, name, item) for name, item in fmi3_items.items()}
    if "road_seed" in fmi2_values:
        start3["road_seed"] = fmi2_values["road_seed"]
    common = dict(stop_time=15.0, output_interval=1e-3, output=OUTPUTS)
    two = fmpy.simulate_fmu(str(fmu_path()), start_values=fmi2_values, **common)
    three = fmpy.simulate_fmu(str(fmi3_file), fmi_type="CoSimulation", start_values=start3, **common)
    assert len(two) == len(three) == 15001
    assert np.array_equal(two["time"], three["time"])
    for name in OUTPUTS:
        peak = np.abs(two[name]).max()
        difference = np.abs(two[name] - three[name]).max()
        assert difference <= 1e-12 * peak, (name, difference, peak)


def slave(md3, unzip3, **instantiate):
    s = FMU3Slave(
        guid=md3.guid,
        unzipDirectory=unzip3,
        modelIdentifier=md3.coSimulation.modelIdentifier,
        instanceName="tdvass",
    )
    s.instantiate(**instantiate)
    return s


def vrs(md, *names):
    by_name = {v.name: v.valueReference for v in md.modelVariables}
    return [by_name[n] for n in names]


def fine_grid(md, fmu):
    """Internal nodes every 0.1 ms (`max_internal_step`), which the
    intermediate-update tests count."""
    fmu.setFloat64(vrs(md, "max_internal_step"), [1e-4])


def test_intermediate_updates_through_fmpy(md3, unzip3):
    seen = []
    holder = {}
    rms = vrs(md3, "rms_body_acceleration")

    def update(env, time, set_requested, get_allowed, step_finished, can_return_early,
               early_return_requested, early_return_time):
        if get_allowed:
            seen.append((time, holder["fmu"].getFloat64(rms)[0]))

    callback = fmi3IntermediateUpdateCallback(update)
    fmu = slave(md3, unzip3, intermediateUpdate=update)
    holder["fmu"] = fmu
    fine_grid(md3, fmu)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 0.005)
    fmu.terminate()
    fmu.freeInstance()
    del callback
    assert len(seen) == 49, [t for t, _ in seen][:5]
    reference = slave(md3, unzip3)
    fine_grid(md3, reference)
    reference.enterInitializationMode(startTime=0.0)
    reference.exitInitializationMode()
    t = 0.0
    for time, inside in seen:
        reference.doStep(t, time - t)
        t = time
        there = reference.getFloat64(rms)[0]
        assert abs(inside - there) <= 1e-12 * abs(there), (time, inside, there)
    reference.terminate()
    reference.freeInstance()


def test_early_return_through_fmpy(md3, unzip3):
    holder = {}

    def update(env, time, set_requested, get_allowed, step_finished, can_return_early,
               early_return_requested, early_return_time):
        if can_return_early and time >= 2e-3 and not holder.get("asked"):
            holder["asked"] = True
            early_return_requested[0] = True

    fmu = slave(md3, unzip3, intermediateUpdate=update, earlyReturnAllowed=True)
    fine_grid(md3, fmu)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    _, terminate, early, last = fmu.doStep(0.0, 0.01)
    assert early and not terminate
    assert last == pytest.approx(2e-3, abs=1e-12)
    _, _, early, last = fmu.doStep(last, 0.01 - last)
    assert not early and last == pytest.approx(0.01, abs=1e-15)
    values = fmu.getFloat64(vrs(md3, *RMS))
    fmu.terminate()
    fmu.freeInstance()
    reference = slave(md3, unzip3)
    fine_grid(md3, reference)
    reference.enterInitializationMode(startTime=0.0)
    reference.exitInitializationMode()
    reference.doStep(0.0, 0.01)
    assert np.allclose(values, reference.getFloat64(vrs(md3, *RMS)), rtol=1e-12, atol=0.0)
    reference.terminate()
    reference.freeInstance()


def test_serialized_state_continues_in_a_fresh_process(md3, unzip3, tmp_path):
    fmu = slave(md3, unzip3)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    for k in range(500):
        fmu.doStep(k * 1e-3, 1e-3)
    state = fmu.getFMUState()
    data = fmu.serializeFMUState(state)
    fmu.freeFMUState(state)
    for k in range(500, 1000):
        fmu.doStep(k * 1e-3, 1e-3)
    here = fmu.getFloat64(vrs(md3, *OUTPUTS))
    fmu.terminate()
    fmu.freeInstance()
    state_file = tmp_path / "state.bin"
    state_file.write_bytes(bytes(data))
    script = f"""
import sys
from fmpy import read_model_description
from fmpy.fmi3 import FMU3Slave
md = read_model_description({str(unzip3)!r})
fmu = FMU3Slave(guid=md.guid, unzipDirectory={str(unzip3)!r}, modelIdentifier='tdvass', instanceName='fresh')
fmu.instantiate()
state = fmu.deserializeFMUState(open({str(state_file)!r}, 'rb').read())
fmu.setFMUState(state)
for k in range(500, 1000):
    fmu.doStep(k * 1e-3, 1e-3)
vr = {{v.name: v.valueReference for v in md.modelVariables}}
print(repr(fmu.getFloat64([vr[n] for n in {OUTPUTS!r}])))
"""
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    there = eval(out.stdout.strip())
    assert there == here


def test_enumeration_start_values_by_name(fmi3_file, md3):
    cs = enumeration_value(md3, "variant", "CS")
    harmonic = enumeration_value(md3, "road", "harmonic")
    assert (cs, harmonic) == (1, 1)
    by_name = fmpy.simulate_fmu(
        str(fmi3_file), fmi_type="CoSimulation", stop_time=1.0,
        start_values={"variant": cs, "road": harmonic}, output=RMS,
    )
    by_code = fmpy.simulate_fmu(str(fmu_path()), stop_time=1.0, start_values={"variant": 1}, output=RMS)
    for name in RMS:
        assert np.allclose(by_name[name], by_code[name], rtol=1e-12, atol=0.0)
