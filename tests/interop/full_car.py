"""The assembled car (target/fmu/full-car.ssp, target/fmu/full-car/) in
every master the suite has, each in a process of its own (a crash of a
master fails its test instead of killing pytest):

    python full_car.py MASTER FMU_DIR STOP_TIME STEP OUT.json

MASTER is one of
- `libcosim-osp`: libcosim from full-car/OspSystemStructure.xml (fixed
  step; the file's own 1 ms step, STEP must be 0.001);
- `libcosim-ecco`: libcosim with the ECCO algorithm, the power bonds and
  settings of full-car/OspSystemStructure_ecco.xml, built through its API
  (`libcosim_ecco` says why; adaptive step, STEP is ignored);
- `libcosim-ssp`: libcosim from full-car.ssp at STEP;
- `ecos-ssp`: ecos from full-car.ssp at STEP (its parameter set
  `full-car`);
- `fmpy-loop`: examples/full_car.py's loop: fmpy's FMU2Slave, five
  instances stepped at STEP, with the components, parameters and
  connections read from the SSD inside full-car.ssp (fmpy's own
  `simulate_ssp` leaves the SSD's parameter bindings out);
- `monolithic`: not a master but the reference, `tdvass car` (the
  command line next to FMU_DIR's `target/fmu`: `target/release/tdvass`),
  the same car as one delay equation with no coupling error.

Writes the car's summary at STOP_TIME as JSON: the chassis's RMS values,
each corner's RMS values and lift-off count, and the master's name.

libcosim's and ecos's fixed-step algorithms are Jacobi schemes: after a
step every output is read, then every input set from the outputs at the
end of the step, then every FMU steps. The fmpy loop does the same, so it
agrees with them to the rounding of their clocks.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

CHASSIS = "chassis"
CORNERS = ["fl", "fr", "rl", "rr"]
CHASSIS_OUTPUTS = [
    "rms_heave_acceleration",
    "rms_pitch_acceleration",
    "rms_roll_acceleration",
    "rms_weighted_seat_acceleration",
    "seat_vibration_dose_value",
]
CORNER_OUTPUTS = ["rms_suspension_deflection", "rms_dynamic_tire_load_ratio", "rms_tire_deflection"]
CORNER_COUNTS = ["lift_off_count"]


def summary(read_real, read_integer) -> dict:
    """The car's summary from `read_real(instance, name)` and
    `read_integer(instance, name)`."""
    return {
        CHASSIS: {name: read_real(CHASSIS, name) for name in CHASSIS_OUTPUTS},
        "corners": {
            corner: {
                **{name: read_real(corner, name) for name in CORNER_OUTPUTS},
                **{name: read_integer(corner, name) for name in CORNER_COUNTS},
            }
            for corner in CORNERS
        },
    }


def steps_of(stop_time: float, step: float) -> int:
    n = round(stop_time / step)
    assert abs(n * step - stop_time) <= 1e-9 * stop_time, (stop_time, step)
    return n


# ------------------------------------------------------------------ libcosim


def run_libcosim(execution, stop_time: float) -> dict:
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimObserver import CosimObserver

    observer = CosimObserver.create_last_value()
    assert execution.add_observer(observer)
    stop_ns = round(stop_time * 1e9)
    assert execution.simulate_until(stop_ns), "libcosim simulate_until failed"
    assert execution.status().current_time >= stop_ns
    index = {info.name.decode(): info.index for info in execution.slave_infos()}
    variables = {
        name: {v.name.decode(): v for v in execution.slave_variables(i)} for name, i in index.items()
    }

    def real(instance, name):
        v = variables[instance][name]
        assert CosimVariableType(v.type) == CosimVariableType.REAL
        return observer.last_real_values(index[instance], [v.reference])[0]

    def integer(instance, name):
        v = variables[instance][name]
        return observer.last_integer_values(index[instance], [v.reference])[0]

    result = summary(real, integer)
    result["time"] = execution.status().current_time / 1e9
    return result


def libcosim_osp(fmu_dir: Path, stop_time: float, step: float, file_name: str) -> dict:
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_osp_config_file(str(fmu_dir / "full-car" / file_name))
    assert execution is not None, "libcosim could not load the OSP system structure"
    return run_libcosim(execution, stop_time)


OSP = "{http://opensimulationplatform.com/MSMI/OSPSystemStructure}"


def libcosim_ecco(fmu_dir: Path, stop_time: float, step: float) -> dict:
    """ECCO as full-car/OspSystemStructure_ecco.xml states it, built through
    libcosim's own API: its simulators, initial values, connections, power
    bonds and ECCO settings. (libcosim's OSP parser, up to its newest
    release, checks the number of distinct bond names against the bonds
    added so far inside its loop over the bonds, so it refuses any file
    with more than one bond; a car has four.)"""
    import xml.etree.ElementTree as ET

    from libcosimpy.CosimAlgorithm import CosimAlgorithm, EccoParams
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.WARNING)
    path = fmu_dir / "full-car" / "OspSystemStructure_ecco.xml"
    root = ET.parse(path).getroot()
    assert root.findtext(f"{OSP}Algorithm") == "ecco"
    ecco = root.find(f"{OSP}EccoConfiguration")
    setting = {child.tag[len(OSP):]: float(child.text) for child in ecco}
    algorithm = CosimAlgorithm.create_ecco_algorithm(EccoParams(
        safety_factor=setting["SafetyFactor"],
        step_size=setting["StepSize"],
        min_step_size=setting["MinimumStepSize"],
        max_step_size=setting["MaximumStepSize"],
        min_change_rate=setting["MinimumChangeRate"],
        max_change_rate=setting["MaximumChangeRate"],
        abs_tolerance=setting["AbsoluteTolerance"],
        rel_tolerance=setting["RelativeTolerance"],
        p_gain=setting["ProportionalGain"],
        i_gain=setting["IntegralGain"],
    ))
    execution = CosimExecution.from_algorithm(algorithm)
    index, refs, keep = {}, {}, []
    for simulator in root.iter(f"{OSP}Simulator"):
        name = simulator.get("name")
        slave = CosimLocalSlave(fmu_path=str((path.parent / simulator.get("source")).resolve()), instance_name=name)
        keep.append(slave)
        index[name] = execution.add_local_slave(slave)
        assert index[name] >= 0, f"libcosim could not add {name}"
        refs[name] = {v.name.decode(): v.reference for v in execution.slave_variables(index[name])}
        for initial in simulator.iter(f"{OSP}InitialValue"):
            variable = initial.get("variable")
            (value,) = list(initial)
            reference = refs[name][variable]
            if value.tag == f"{OSP}Integer":
                assert execution.integer_initial_value(index[name], reference, int(value.get("value")))
            else:
                assert execution.real_initial_value(index[name], reference, float(value.get("value")))
    bonds = {}
    for connection in root.iter(f"{OSP}VariableConnection"):
        (a, b) = connection.iter(f"{OSP}Variable")
        source, sink = (a, b) if a.get("causality") == "output" else (b, a)
        status = execution.connect_real_variables(
            index[source.get("simulator")], refs[source.get("simulator")][source.get("name")],
            index[sink.get("simulator")], refs[sink.get("simulator")][sink.get("name")],
        )
        assert status == 0, f"libcosim refused {source.get('name')} -> {sink.get('name')}"
        if connection.get("powerBond"):
            bonds.setdefault(connection.get("powerBond"), []).append((source, sink))
    assert len(bonds) == 4, bonds
    for name, pair in bonds.items():
        # One side's output and input, then the other's.
        (out_a, in_b), (out_b, in_a) = pair
        assert out_a.get("simulator") == in_a.get("simulator") and out_b.get("simulator") == in_b.get("simulator")
        status = algorithm.add_power_bond(
            index[out_a.get("simulator")], refs[out_a.get("simulator")][out_a.get("name")],
            refs[in_a.get("simulator")][in_a.get("name")],
            index[out_b.get("simulator")], refs[out_b.get("simulator")][out_b.get("name")],
            refs[in_b.get("simulator")][in_b.get("name")],
        )
        assert status == 0, f"libcosim refused the power bond {name}"
    return run_libcosim(execution, stop_time)


def libcosim_ssp(fmu_dir: Path, stop_time: float, step: float) -> dict:
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_ssp_file(str(fmu_dir / "full-car.ssp"), step_size=round(step * 1e9))
    assert execution is not None, "libcosim could not load full-car.ssp"
    return run_libcosim(execution, stop_time)


# ---------------------------------------------------------------------- ecos


def ecos_ssp(fmu_dir: Path, stop_time: float, step: float) -> dict:
    from ecospy import EcosLib, EcosSimulation

    simulation = EcosSimulation(step_size=step, ssp_path=str(fmu_dir / "full-car.ssp"))
    assert simulation.init(parameter_set="full-car"), EcosLib.get_last_error()
    simulation.step(steps_of(stop_time, step))
    result = summary(
        lambda instance, name: simulation.get_real(f"{instance}::{name}"),
        lambda instance, name: simulation.get_integer(f"{instance}::{name}"),
    )
    result["time"] = simulation.get_time()
    simulation.terminate()
    simulation.free()
    return result


# ---------------------------------------------------------------- fmpy loop


def fmpy_loop(fmu_dir: Path, stop_time: float, step: float) -> dict:
    # The example's loop (examples/full_car.py), which reads the SSD.
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
    from full_car import run_car

    times, _, result = run_car(fmu_dir / "full-car.ssp", stop_time, step)
    result["time"] = float(times[-1])
    return result


# ---------------------------------------------------------- the exact car


def monolithic(fmu_dir: Path, stop_time: float, step: float) -> dict:
    """`tdvass car` (the same car as one delay equation, STEP is ignored):
    the SSD's road (ISO 8608 class C at 20 m/s, seed 1 on the left track,
    the next seed on the right, the rear wheels a wheelbase behind) and
    every other parameter at its default, as the FMUs'."""
    import subprocess

    binary = fmu_dir.parent / "release" / ("tdvass.exe" if sys.platform == "win32" else "tdvass")
    done = subprocess.run(
        [str(binary), "car", "--road", "iso8608", "--duration", repr(stop_time), "--json"],
        capture_output=True, text=True, check=True, timeout=600,
    )
    car = json.loads(done.stdout)
    result = summary(
        lambda instance, name: car[name] if instance == CHASSIS else car["corners"][instance][name],
        lambda instance, name: car["corners"][instance][name],
    )
    result["time"] = float(car["duration"])
    return result


MASTERS = {
    "libcosim-osp": lambda d, t, h: libcosim_osp(d, t, h, "OspSystemStructure.xml"),
    "libcosim-ecco": libcosim_ecco,
    "libcosim-ssp": libcosim_ssp,
    "ecos-ssp": ecos_ssp,
    "fmpy-loop": fmpy_loop,
    "monolithic": monolithic,
}


def main():
    master, fmu_dir, stop_time, step, out = sys.argv[1:]
    result = MASTERS[master](Path(fmu_dir), float(stop_time), float(step))
    result["master"] = master
    Path(out).write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
