"""Runs one experiment in libcosim (libcosimpy) or ecos (ecospy), in its own
process: a crash of the master (libcosim dereferences a NULL instance, for
one) fails the test that started it instead of killing pytest.

    python run_master.py libcosim|ecos FMU EXPERIMENT_JSON OUT.npz

Writes `times` (the communication times the FMU was given, s), `rows` (the
outputs at each, after the start), `version` and, from libcosim, the
variables it found (`variables`: JSON name -> type).
"""

from __future__ import annotations

import json
import sys

import numpy as np

SINK, SOURCE = "sink", "source"


def run_libcosim(fmu: str, experiment: dict):
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave
    from libcosimpy.__about__ import __version__
    from libcosimpy._internal import get_last_error_message

    log_output_level(CosimLogLevel.WARNING)
    # libcosim's clock is an integer number of nanoseconds; the FMU gets
    # t_k = (k * step_ns) / 1e9 (a correctly rounded division), which is not
    # always fmpy's k * 0.001.
    step_ns = round(experiment["step_size"] * 1e9)
    stop_ns = round(experiment["stop_time"] * 1e9)
    n = stop_ns // step_ns
    assert n * step_ns == stop_ns
    execution = CosimExecution.from_step_size(step_ns)

    def add(name, start_values):
        slave = CosimLocalSlave(fmu_path=fmu, instance_name=name)
        index = execution.add_local_slave(slave)
        assert index >= 0, f"libcosim could not add {name}"
        # Value references from libcosim's own reading of modelDescription.xml.
        variables = {v.name.decode(): v for v in execution.slave_variables(index)}
        for key, value in start_values.items():
            v = variables[key]
            if CosimVariableType(v.type) == CosimVariableType.INTEGER:
                ok = execution.integer_initial_value(index, v.reference, int(value))
            else:
                ok = execution.real_initial_value(index, v.reference, float(value))
            assert ok, f"libcosim refused the initial value {key} = {value}"
        return index, variables, slave

    sink, variables, sink_slave = add(SINK, experiment["start_values"])
    seen = {name: CosimVariableType(v.type).name for name, v in variables.items()}
    keep = [sink_slave]
    if experiment["source"] is not None:
        source, source_variables, source_slave = add(SOURCE, experiment["source"])
        keep.append(source_slave)
        # libcosimpy returns libcosimc's status here (0 = success), not a bool.
        status = execution.connect_real_variables(
            source, source_variables["road_displacement"].reference, sink, variables["x_g"].reference
        )
        assert status == 0, f"libcosim refused the connection road_displacement -> x_g: {get_last_error_message()}"
    observer = CosimObserver.create_time_series(buffer_size=n + 16)
    assert execution.add_observer(observer)
    vrs = [variables[name].reference for name in experiment["outputs"]]
    for vr in vrs:
        assert observer.start_time_series(sink, vr, CosimVariableType.REAL)
    assert execution.simulate_until(stop_ns), "libcosim simulate_until failed"
    status = execution.status()
    assert status.current_time == stop_ns, status
    columns = []
    for vr in vrs:
        # From step 1: libcosimpy 0.0.6 trims as many samples as there are
        # step numbers 0 in the answer, which drops one when step 0 is asked.
        time_points, steps, values = observer.time_series_real_samples(sink, vr, from_step=1, sample_count=n)
        assert list(steps) == list(range(1, n + 1)), "libcosim lost samples"
        columns.append(values)
    times = np.array([t / 1_000_000_000 for t in time_points])
    version = f"libcosimpy {__version__} (libcosim {libcosim_version()})"
    return times, np.column_stack(columns), version, seen


def libcosim_version() -> str:
    from ctypes import Structure, c_int

    from libcosimpy._internal import libcosimc

    class Version(Structure):
        _fields_ = [("major", c_int), ("minor", c_int), ("patch", c_int)]

    function = libcosimc().cosim_libcosim_version
    function.restype = Version
    v = function()
    return f"{v.major}.{v.minor}.{v.patch}"


def run_ecos(fmu: str, experiment: dict):
    from ecospy import EcosLib, EcosSimulation, EcosSimulationStructure

    structure = EcosSimulationStructure()
    structure.add_model(SINK, fmu)
    parameters = {f"{SINK}::{k}": v for k, v in experiment["start_values"].items()}
    if experiment["source"] is not None:
        structure.add_model(SOURCE, fmu)
        structure.make_real_connection(f"{SOURCE}::road_displacement", f"{SINK}::x_g")
        parameters.update({f"{SOURCE}::{k}": v for k, v in experiment["source"].items()})
    if parameters:
        # ints become Integer parameters, floats Real ones.
        assert structure.add_parameter_set("start", parameters), EcosLib.get_last_error()
    simulation = EcosSimulation(structure=structure, step_size=experiment["step_size"])
    assert simulation.init(parameter_set="start" if parameters else None), EcosLib.get_last_error()
    for key, value in experiment["start_values"].items():
        read = simulation.get_integer if isinstance(value, int) else simulation.get_real
        assert read(f"{SINK}::{key}") == value, key
    n = round(experiment["stop_time"] / experiment["step_size"])
    names = [f"{SINK}::{name}" for name in experiment["outputs"]]
    times, rows = np.empty(n), np.empty((n, len(names)))
    for k in range(n):
        # ecos's clock is a running sum, t_{k+1} = t_k + h, returned by step().
        times[k] = simulation.step()
        rows[k] = [simulation.get_real(name) for name in names]
    simulation.terminate()
    simulation.free()
    structure.free()
    version = EcosLib.version()
    return times, rows, f"ecospy {version.major}.{version.minor}.{version.patch}", {}


def main():
    master, fmu, experiment, out = sys.argv[1:]
    experiment = json.loads(experiment)
    times, rows, version, variables = {"libcosim": run_libcosim, "ecos": run_ecos}[master](fmu, experiment)
    np.savez(out, times=times, rows=rows, version=version, variables=json.dumps(variables))


if __name__ == "__main__":
    main()
