"""Writes the seed inputs of the `deserialize` fuzz target from states of
the real library (run after building the FMU):

    python fuzz/make_seeds.py

Each seed is `[mode 1][steps][payload]`: the target puts the payload behind
a valid header, so the fuzzer starts from well-formed states of every kind.
"""

import sys
from pathlib import Path

here = Path(__file__).resolve().parent
sys.path.insert(0, str(here.parent / "tests" / "robustness"))
import fmi2  # noqa: E402

CONFIGS = {
    "tdvass-harmonic": {},
    "cs": {"variant": 1},
    "pvass-iso": {"variant": 2, "road": 2},
    "paper": {"road": 3, "road_seed": 7},
    "input": {"road": 0, "x_g": 0.01},
    "long-delay": {"tau": 0.03, "g": 2000.0},
    "folded-delay": {"tau": 1e-8},
}


def main():
    lib = fmi2.load()
    out = here / "corpus" / "deserialize"
    out.mkdir(parents=True, exist_ok=True)
    written = 0

    def save(name, inst, state, steps=0x1B):
        nonlocal written
        data = inst.serialize(state)
        at, _ = fmi2.serialized_fields(data)
        (out / f"seed-{name}").write_bytes(bytes([1, steps]) + data[at:])
        written += 1

    for name, values in CONFIGS.items():
        inst = fmi2.Instance(lib)
        status, state = inst.get_state()
        if name == "tdvass-harmonic":
            save("instantiated", inst, state)
        inst.initialize(stop=10.0, **values)
        for h in (0.0123, 0.05):
            assert inst.step(h) == fmi2.OK
        inst.lib.fmi2GetFMUstate(inst.c, fmi2.byref(state))
        save(name, inst, state)
        inst.free()
    # stepFailed after a divergence, terminated.
    inst = fmi2.Instance(lib)
    inst.initialize(g=-40000.0, tau=0.11, x_s_start=0.01)
    while inst.step(1.0) == fmi2.OK:
        pass
    status, state = inst.get_state()
    save("step-failed", inst, state)
    inst.lib.fmi2Terminate(inst.c)
    inst.lib.fmi2GetFMUstate(inst.c, fmi2.byref(state))
    save("terminated", inst, state)
    inst.free()
    # The corner (mode bits 0x40) and the chassis (0x80), the same library:
    # a running state with its inputs set.
    for name, fmu, mode, values, inputs in (
        ("corner", fmi2.corner_fmu_file(), 0x41, {"road_delay": 0.05, "road_phase": 0.3},
         {"body_displacement": 0.002, "body_velocity": -0.01}),
        ("chassis", fmi2.fmu_file().with_name("tdvass-chassis.fmu"), 0x81, {},
         {"force_fl": 300.0, "force_rr": -120.0}),
    ):
        inst = fmi2.Instance(lib, fmu=fmu)
        inst.initialize(stop=10.0, **values)
        assert inst.set(**inputs) == fmi2.OK, inst.log.last()
        assert inst.step(0.0123) == fmi2.OK, inst.log.last()
        status, state = inst.get_state()
        data = inst.serialize(state)
        at, _ = fmi2.serialized_fields(data)
        (out / f"seed-{name}").write_bytes(bytes([mode, 0x1B]) + data[at:])
        written += 1
        inst.free()
    print(f"{written} seeds in {out}")


if __name__ == "__main__":
    main()
