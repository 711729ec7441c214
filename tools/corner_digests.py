#!/usr/bin/env python3
"""Bit-identity digests of the corner FMUs' outputs, for a before/after
comparison of a refactor (tools/output_digests.py covers the quarter car).

    .venv/bin/python tools/corner_digests.py target/fmu > corner.txt

FMU_DIR holds `tdvass-corner.fmu` and `tdvass-corner-fmi3.fmu`. One line a
case, `<case> <first 16 hex digits of a sha256>`:

  * Co-Simulation (FMI 2.0, fmpy's FMU2Slave): 1 500 steps of 1 ms with the
    body attachment set before every step on a sine, holding
    (`input_extrapolation = 0`) and extrapolating (1), TDVASS unilateral
    at τ = 0.2 ms and PVASS; the bits of every Real output after every
    step.
  * Model Exchange (both versions, the tests' own master): 0.3 s of RK4 at
    1 ms completing every step, the body attachment and (on the input
    road) x_g held; the bits of the derivatives, the Real outputs and the
    directional derivatives of both with respect to the states and the
    body attachment at the end.
"""

import hashlib
import struct
import sys
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "python"))
from me_master import RK4, ModelExchangeMaster, explicit  # noqa: E402

CO_SIMULATION = [{"variant": 3, "tau": 2e-4, "tire_contact": 1}, {"variant": 2}]
MODEL_EXCHANGE = [{"variant": 3, "tau": 2e-4, "road": 0, "tire_contact": 1}, {"variant": 3, "tau": 0.011}]


def real_outputs(md):
    return [v.valueReference for v in md.modelVariables
            if v.causality == "output" and v.type in ("Real", "Float64")]


def co_simulation(path, start, extrapolation):
    md = read_model_description(path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    outputs = real_outputs(md)
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(path),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="corner")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    for name, value in start.items():
        (slave.setInteger if isinstance(value, int) else slave.setReal)([vr[name]], [value])
    slave.setInteger([vr["input_extrapolation"]], [extrapolation])
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    digest = hashlib.sha256()
    t = 0.0
    for _ in range(1500):
        slave.setReal([vr["body_displacement"], vr["body_velocity"]],
                      [0.02 * np.sin(9 * t), 0.18 * np.cos(9 * t)])
        slave.doStep(t, 1e-3)
        t += 1e-3
        digest.update(struct.pack(f"<{len(outputs)}d", *slave.getReal(outputs)))
    slave.terminate()
    slave.freeInstance()
    return digest.hexdigest()[:16]


def model_exchange(path, start):
    md = read_model_description(path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    outputs = real_outputs(md)
    master = ModelExchangeMaster(path, start, extract(path))
    master.set("body_displacement", 0.004)
    master.set("body_velocity", -0.03)
    if start.get("road") == 0:
        master.set("x_g", 0.01)
    explicit(master, RK4, 0.3, 1e-3, complete=True)
    digest = hashlib.sha256()
    digest.update(struct.pack(f"<{master.n}d", *master.derivatives(master.t, master.x)))
    read = master.fmu.getFloat64 if master.fmi3 else master.fmu.getReal
    digest.update(struct.pack(f"<{len(outputs)}d", *read(outputs)))
    knowns = master.state_vrs + [vr["body_displacement"], vr["body_velocity"]]
    digest.update(master.partials(master.derivative_vrs + outputs, knowns).tobytes())
    master.free()
    return digest.hexdigest()[:16]


def main():
    folder = Path(sys.argv[1])
    fmi2, fmi3 = str(folder / "tdvass-corner.fmu"), str(folder / "tdvass-corner-fmi3.fmu")
    for extrapolation in (0, 1):
        for start in CO_SIMULATION:
            print(f"fmi2/cs/extrapolation={extrapolation}/{start}", co_simulation(fmi2, start, extrapolation))
    for name, path in (("fmi2", fmi2), ("fmi3", fmi3)):
        for start in MODEL_EXCHANGE:
            print(f"{name}/me/{start}", model_exchange(path, start))


if __name__ == "__main__":
    main()
