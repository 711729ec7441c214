"""The assembled car (target/fmu/full-car.ssp, target/fmu/full-car/) in
every master the suite has, each in a process of its own (a crash of a
master fails its test instead of killing pytest):

    python full_car.py MASTER FMU_DIR STOP_TIME STEP OUT.json [SCENARIO]

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

SCENARIO, if given, changes the car: a name of `SCENARIOS` or a JSON file,
either of them `{instance: {parameter: value}}` on top of the SSD's
parameters (integers for the FMUs' Integer parameters: `road`,
`road_class`, `tire_contact`, ...). Every master applies it through its
own API: libcosim as initial values, ecos by setting the variables before
`init`, the fmpy loop through `run_car`'s `overrides`, and `tdvass car`
through its flags (`car_flags`, which refuses a car it cannot state: each
corner's `static_load` must be its share of the body's weight and the rear
wheels' `road_delay` the wheelbase over the speed, as in `tdvass car`).

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
STANDARD_GRAVITY = 9.80665  # g0 (m/s2), the corners' and tdvass car's


# ----------------------------------------------------------------- scenarios


def car_parameters(chassis: dict, road_class: int, vehicle_speed: float, left_seed: int, right_seed: int,
                   tire_contact: int) -> dict:
    """`{instance: {parameter: value}}` of a car on the ISO 8608 road: the
    chassis's parameters `chassis` (mass, a, b and any other), each
    corner's share of the body's weight as its static load (front
    m g0 b / (a + b) / 2, rear m g0 a / (a + b) / 2, the shares of
    `tdvass car`), the rear wheels a wheelbase behind, `left_seed` under
    the left wheels and `right_seed` under the right ones."""
    mass, a, b = chassis["mass"], chassis["a"], chassis["b"]
    parameters = {CHASSIS: dict(chassis)}
    for corner in CORNERS:
        front = corner[0] == "f"
        share = mass * (b if front else a) / (a + b) / 2.0
        parameters[corner] = {
            "road": 2,
            "road_class": road_class,
            "vehicle_speed": vehicle_speed,
            "road_seed": left_seed if corner[1] == "l" else right_seed,
            "road_delay": 0.0 if front else (a + b) / vehicle_speed,
            "static_load": share * STANDARD_GRAVITY,
            "tire_contact": tire_contact,
        }
    return parameters


# A sedan whose front and rear do not decouple: the centre of gravity ahead
# of the middle (a = 1.2 m, b = 1.4 m) and the pitch inertia 0.9 m a b
# (the dynamic index k^2 / (a b) of 0.9; with the default m a b, index 1,
# front and rear decouple).
SEDAN = {"mass": 1380.0, "a": 1.2, "b": 1.4, "pitch_inertia": 0.9 * 1380.0 * 1.2 * 1.4, "roll_inertia": 400.0,
         "track_front": 1.5, "track_rear": 1.5}


def step_parameters(chassis: dict, corner: str, height: float) -> dict:
    """`{instance: {parameter: value}}` of a car at rest whose `corner`
    wheel's road steps up by `height` (m) at the start while the others'
    stay flat: every corner on the input road (`road = 0`) with its `x_g`
    held, the linear tire."""
    parameters = car_parameters(chassis, road_class=3, vehicle_speed=20.0, left_seed=1, right_seed=1,
                                tire_contact=0)
    for name in CORNERS:
        parameters[name]["road"] = 0
        # The input road is the road as the wheel sees it: no delay.
        parameters[name]["road_delay"] = 0.0
        parameters[name]["x_g"] = height if name == corner else 0.0
    return parameters


SCENARIOS = {
    # The same class C road under both tracks at 20 m/s, the linear tire.
    "sedan-c": car_parameters(SEDAN, road_class=3, vehicle_speed=20.0, left_seed=1, right_seed=1, tire_contact=0),
    # Class E at 30 m/s, a road of its own under each track, the tire that
    # cannot pull: the wheels lift off.
    "sedan-e": car_parameters(SEDAN, road_class=5, vehicle_speed=30.0, left_seed=1, right_seed=2, tire_contact=1),
    # A 2 cm step under the front left wheel only, at the start: the car
    # heaves, pitches and rolls.
    "sedan-step": step_parameters(SEDAN, "fl", 0.02),
    # The SSD's car with every input held over a communication step (the
    # FMI default) instead of extrapolated (the SSD's input_extrapolation = 1).
    "hold": {instance: {"input_extrapolation": 0} for instance in [CHASSIS, *CORNERS]},
}


def scenario_parameters(scenario: str | None) -> dict:
    """The overrides `{instance: {parameter: value}}` of `scenario`: a name
    of SCENARIOS, a JSON file, or none."""
    if not scenario:
        return {}
    if scenario in SCENARIOS:
        return SCENARIOS[scenario]
    return json.loads(Path(scenario).read_text())


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


def run_libcosim(execution, stop_time: float, overrides: dict, last_step: float = 0.0) -> dict:
    """Runs `execution` to `stop_time`, the parameters `overrides` set as
    initial values first (after the configuration's own, so they win).
    libcosim stops once less than 1 % of the last step is left: an adaptive
    algorithm whose steps reach `last_step` may end that much short."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimObserver import CosimObserver

    index = {info.name.decode(): info.index for info in execution.slave_infos()}
    variables = {
        name: {v.name.decode(): v for v in execution.slave_variables(i)} for name, i in index.items()
    }
    for instance, parameters in overrides.items():
        for name, value in parameters.items():
            v = variables[instance][name]
            if CosimVariableType(v.type) == CosimVariableType.INTEGER:
                assert execution.integer_initial_value(index[instance], v.reference, int(value)), (instance, name)
            else:
                assert CosimVariableType(v.type) == CosimVariableType.REAL, (instance, name)
                assert execution.real_initial_value(index[instance], v.reference, float(value)), (instance, name)
    observer = CosimObserver.create_last_value()
    assert execution.add_observer(observer)
    stop_ns = round(stop_time * 1e9)
    assert execution.simulate_until(stop_ns), "libcosim simulate_until failed"
    assert execution.status().current_time >= stop_ns - round(0.01 * last_step * 1e9)

    def real(instance, name):
        v = variables[instance][name]
        assert CosimVariableType(v.type) == CosimVariableType.REAL
        return observer.last_real_values(index[instance], [v.reference])[0]

    def integer(instance, name):
        v = variables[instance][name]
        assert CosimVariableType(v.type) == CosimVariableType.INTEGER
        return observer.last_integer_values(index[instance], [v.reference])[0]

    # The parameters the FMUs ran with are the scenario's.
    for instance, parameters in overrides.items():
        for name, value in parameters.items():
            is_integer = CosimVariableType(variables[instance][name].type) == CosimVariableType.INTEGER
            read = integer if is_integer else real
            assert read(instance, name) == value, (instance, name, read(instance, name), value)
    result = summary(real, integer)
    result["time"] = execution.status().current_time / 1e9
    return result


def libcosim_osp(fmu_dir: Path, stop_time: float, step: float, overrides: dict, file_name: str) -> dict:
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_osp_config_file(str(fmu_dir / "full-car" / file_name))
    assert execution is not None, "libcosim could not load the OSP system structure"
    return run_libcosim(execution, stop_time, overrides)


OSP = "{http://opensimulationplatform.com/MSMI/OSPSystemStructure}"


def libcosim_ecco(fmu_dir: Path, stop_time: float, step: float, overrides: dict) -> dict:
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
    return run_libcosim(execution, stop_time, overrides, last_step=setting["MaximumStepSize"])


def libcosim_ssp(fmu_dir: Path, stop_time: float, step: float, overrides: dict) -> dict:
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_ssp_file(str(fmu_dir / "full-car.ssp"), step_size=round(step * 1e9))
    assert execution is not None, "libcosim could not load full-car.ssp"
    return run_libcosim(execution, stop_time, overrides)


# ---------------------------------------------------------------------- ecos


def model_variables(fmu_dir: Path) -> dict:
    """`{instance: {name: fmpy ScalarVariable}}` of the SSD's instances."""
    import zipfile
    import xml.etree.ElementTree as ET

    from fmpy import read_model_description

    ssd = "{http://ssp-standard.org/SSP1/SystemStructureDescription}"
    with zipfile.ZipFile(fmu_dir / "full-car.ssp") as archive:
        root = ET.fromstring(archive.read("SystemStructure.ssd"))
    sources = {c.get("name"): Path(c.get("source")).name for c in root.iter(f"{ssd}Component")}
    descriptions = {source: read_model_description(str(fmu_dir / source)) for source in set(sources.values())}
    return {
        instance: {v.name: v for v in descriptions[source].modelVariables} for instance, source in sources.items()
    }


def integer_parameters(fmu_dir: Path) -> dict:
    """`{instance: {names of its Integer variables}}`."""
    return {
        instance: {name for name, v in variables.items() if v.type == "Integer"}
        for instance, variables in model_variables(fmu_dir).items()
    }



def ecos_ssp(fmu_dir: Path, stop_time: float, step: float, overrides: dict) -> dict:
    from ecospy import EcosLib, EcosSimulation

    simulation = EcosSimulation(step_size=step, ssp_path=str(fmu_dir / "full-car.ssp"))
    if not overrides:
        assert simulation.init(parameter_set="full-car"), EcosLib.get_last_error()
    else:
        # ecos applies a parameter set inside `init`, over any value set
        # before: so no parameter set, and the SSD's values and the
        # overrides set before `init` (as the variables' start values).
        components, _ = example().read_ssd(fmu_dir / "full-car.ssp")
        integers = integer_parameters(fmu_dir)
        wanted = {
            instance: {**given, **overrides.get(instance, {})} for instance, (_, given) in components.items()
        }
        for instance, parameters in wanted.items():
            for name, value in parameters.items():
                if name in integers[instance]:
                    simulation.set_integer(f"{instance}::{name}", int(value))
                else:
                    simulation.set_real(f"{instance}::{name}", float(value))
        assert simulation.init(), EcosLib.get_last_error()
        # The FMUs run with these values.
        for instance, parameters in wanted.items():
            for name, value in parameters.items():
                get = simulation.get_integer if name in integers[instance] else simulation.get_real
                assert get(f"{instance}::{name}") == value, (instance, name, get(f"{instance}::{name}"), value)
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


def fmpy_loop(fmu_dir: Path, stop_time: float, step: float, overrides: dict) -> dict:
    # The example's loop (examples/full_car.py), which reads the SSD.
    times, _, result = example().run_car(fmu_dir / "full-car.ssp", stop_time, step, overrides=overrides)
    result["time"] = float(times[-1])
    return result


# ---------------------------------------------------------- the exact car


def example():
    """examples/full_car.py (its SSD reader and loop), as a module."""
    import importlib.util

    examples = Path(__file__).resolve().parents[2] / "examples"
    sys.path.insert(0, str(examples))
    spec = importlib.util.spec_from_file_location("full_car_example", examples / "full_car.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# `tdvass car`'s flags: the chassis's parameters, and the corners' that must
# be alike on all four.
CHASSIS_FLAGS = ["mass", "a", "b", "track_front", "track_rear", "pitch_inertia", "roll_inertia", "seat_x", "seat_y"]
CORNER_FLAGS = ["variant", "m_h", "m_t", "k_s", "k_h", "k_t", "c_s", "c_h", "g", "tau", "road_class",
                "vehicle_speed", "road_cutoff_frequency", "tire_contact"]
# The corners' parameters and inputs the flags account for otherwise.
CORNER_DERIVED = ["road", "road_seed", "road_delay", "static_load", "x_g"]
# How a co-simulation continues its inputs over a step: nothing to the car.
COUPLING_ONLY = ["input_extrapolation"]


def car_flags(fmu_dir: Path, overrides: dict, work: Path) -> list[str]:
    """The `tdvass car` flags of the SSD's car with `overrides`: every
    parameter the car has, from the FMUs' defaults, the SSD's values and the
    overrides. Corners on the input road (`road = 0`) with their `x_g` held
    become roads of their own (`--corner-road`, a one-sample file in
    `work`). Refuses (ValueError) a car `tdvass car` does not state: any
    other parameter changed, corners unlike one another, a road other than
    ISO 8608 or held inputs, a static load other than the corner's share of
    the body's weight, a rear road delay other than the wheelbase over the
    speed."""
    variables = model_variables(fmu_dir)
    components, _ = example().read_ssd(fmu_dir / "full-car.ssp")
    effective = {}
    for instance, names in variables.items():
        given = {**components[instance][1], **overrides.get(instance, {})}
        known = CHASSIS_FLAGS if instance == CHASSIS else CORNER_FLAGS + CORNER_DERIVED
        other = set(given) - set(known) - set(COUPLING_ONLY)
        if other:
            raise ValueError(f"tdvass car has no flag for {instance}'s {sorted(other)}")
        cast = {"Integer": int, "Real": float}
        effective[instance] = {
            name: cast[names[name].type](given.get(name, names[name].start)) for name in known
        }
    chassis = effective[CHASSIS]
    flags = ["--road", "iso8608"]
    for name in CHASSIS_FLAGS:
        flags += [f"--{name.replace('_', '-')}", repr(chassis[name])]
    corners = [effective[c] for c in CORNERS]
    for name in CORNER_FLAGS:
        values = {c[name] for c in corners}
        if len(values) != 1:
            raise ValueError(f"the corners' {name} differ: {values}")
        (value,) = values
        if name == "tire_contact":
            flags += ["--tire-contact", ["bilateral", "unilateral"][value]]
        else:
            flags += [f"--{name.replace('_', '-')}", repr(value)]
    fl, fr, rl, rr = corners
    roads = {c["road"] for c in corners}
    if roads == {0}:
        # Each wheel's held x_g: a road of its own.
        for corner, c in zip(CORNERS, corners):
            path = work / f"road_{corner}.csv"
            path.write_text(f"t,x_g\n0,{c['x_g']!r}\n")
            flags += ["--corner-road", f"{corner}=file:{path}"]
    elif roads != {2}:
        raise ValueError("tdvass car's corners here roll on the ISO 8608 road (road = 2) or on held inputs (road = 0)")
    elif any(c["x_g"] != 0.0 for c in corners):
        raise ValueError("x_g is the road only when road = 0")
    if fl["road_seed"] != rl["road_seed"] or fr["road_seed"] != rr["road_seed"]:
        raise ValueError("a rear wheel rolls on its front wheel's road")
    flags += ["--road-seed", str(fl["road_seed"]), "--right-seed", str(fr["road_seed"])]
    mass, a, b = chassis["mass"], chassis["a"], chassis["b"]
    wheelbase_delay = (a + b) / fl["vehicle_speed"]
    for corner, c in zip(CORNERS, corners):
        front = corner[0] == "f"
        delay = 0.0 if front else wheelbase_delay
        share = mass * (b if front else a) / (a + b) / 2.0 * STANDARD_GRAVITY
        if roads == {2} and abs(c["road_delay"] - delay) > 1e-12 * wheelbase_delay:
            raise ValueError(f"{corner}'s road_delay {c['road_delay']} is not {delay}")
        if abs(c["static_load"] - share) > 1e-12 * share:
            raise ValueError(f"{corner}'s static_load {c['static_load']} is not its share {share}")
    return flags


def monolithic(fmu_dir: Path, stop_time: float, step: float, overrides: dict) -> dict:
    """`tdvass car` (the same car as one delay equation, STEP is ignored):
    the SSD's car (ISO 8608 class C at 20 m/s, seed 1 on the left track,
    the next seed on the right, the rear wheels a wheelbase behind, every
    other parameter at the FMUs' default) with `overrides`, as `car_flags`
    states it."""
    import subprocess
    import tempfile

    binary = fmu_dir.parent / "release" / ("tdvass.exe" if sys.platform == "win32" else "tdvass")
    with tempfile.TemporaryDirectory() as work:
        done = subprocess.run(
            [str(binary), "car", *car_flags(fmu_dir, overrides, Path(work)), "--duration", repr(stop_time),
             "--json"],
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
    "libcosim-osp": lambda d, t, h, o: libcosim_osp(d, t, h, o, "OspSystemStructure.xml"),
    "libcosim-ecco": libcosim_ecco,
    "libcosim-ssp": libcosim_ssp,
    "ecos-ssp": ecos_ssp,
    "fmpy-loop": fmpy_loop,
    "monolithic": monolithic,
}


def main():
    master, fmu_dir, stop_time, step, out, *scenario = sys.argv[1:]
    assert len(scenario) <= 1, "usage: full_car.py MASTER FMU_DIR STOP_TIME STEP OUT.json [SCENARIO]"
    overrides = scenario_parameters(scenario[0] if scenario else None)
    result = MASTERS[master](Path(fmu_dir), float(stop_time), float(step), overrides)
    result["master"] = master
    if scenario:
        result["scenario"] = scenario[0]
    Path(out).write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
