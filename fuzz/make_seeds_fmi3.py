"""Writes the seed inputs of the `api_sequence_fmi3` fuzz target: call
sequences in the target's byte encoding (see
fuzz_targets/api_sequence_fmi3.rs) that reach Step Mode with intermediate
updates, an early return, refused calls inside an update, Configuration
Mode with the rightmost_roots array, and FMU states moved between two
instances (also under the FMI 2.0 GUID).

    python fuzz/make_seeds_fmi3.py
"""

from pathlib import Path

here = Path(__file__).resolve().parent

# Operation codes of the target (`b.u8() % 24`).
INSTANTIATE, EXIT_INIT, ENTER_INIT, RESET, GET_ALL, ROOTS, DO_STEP = 0, 3, 2, 5, 8, 9, 10
GET_STATE, SET_STATE, FREE_STATE, SERIALIZE, DERIVATIVES, CONFIGURATION, NOT_APPLICABLE = 13, 14, 15, 16, 17, 19, 21
# Indices into STEPS and into common.rs's INTERESTING values.
STEP_1MS, STEP_10MS, STEP_50MS = 1, 3, 5
ONE = [2, 2]  # real(): an interesting value, index 2 = 1.0
# get_all(): the right count, non-NULL pointers.
GET_ARGS = [3, 1, 1, 1, 1, 1, 1]


def instantiate(slot, early=True, callback=True):
    return [INSTANTIATE, slot, 0, 0, (1 if early else 0) | (2 if callback else 0), 1, 0]


def initialize(slot):
    # start 0, stop 1 s (defined), no tolerance.
    return [ENTER_INIT, slot, 1, *ONE, 0, *ONE, 1, EXIT_INIT, slot]


def do_step(slot, step, script=()):
    return [DO_STEP, slot, 1, 1, step, 0, len(script), *script, 0, *GET_ARGS]


def update(*actions):
    """One intermediate update's script: up to two actions."""
    return [len(actions), *[a for action in actions for a in action]]


READ_OUTPUTS = [0, 3, 1, 2, 5, 8, *GET_ARGS]  # x_s, v_s ... (30 + k)
SET_X_G = [2, 3, 15]  # x_g = 0.1
REFUSED_INSIDE = [4]
EARLY_RETURN = [6]
THIN = [5, 2]  # intermediate_update_interval = 1e-3

SEEDS = {
    "updates-read-and-set": [
        *instantiate(0), *initialize(0),
        *do_step(0, STEP_1MS, [*update(READ_OUTPUTS, SET_X_G), *update(SET_X_G), *update(READ_OUTPUTS)]),
        *do_step(0, STEP_10MS, update(THIN)),
    ],
    "early-return": [
        *instantiate(0), *initialize(0),
        *do_step(0, STEP_10MS, [*update(READ_OUTPUTS), *update(EARLY_RETURN)]),
        *do_step(0, STEP_10MS),
    ],
    "refused-inside-update": [
        *instantiate(0), *initialize(0),
        *do_step(0, STEP_1MS, update(REFUSED_INSIDE, READ_OUTPUTS)),
        NOT_APPLICABLE, 0, 2, 2,
    ],
    "configuration-and-roots": [
        *instantiate(0, early=False, callback=False),
        CONFIGURATION, 0, 1, 3, 1,  # root_count = 6, read back, exit
        *initialize(0),
        ROOTS, 0, 1, 12,  # the 6 x 2 array
        *do_step(0, STEP_50MS),
        DERIVATIVES, 0, 1, 1, 2, 30, 2, 30, 1, 3, 3, *ONE, 1, 1, 1, 1,  # d x_s / d x_s
    ],
    "states-between-instances": [
        *instantiate(0), *initialize(0), *instantiate(1, callback=False), *initialize(1),
        *do_step(0, STEP_10MS, update(READ_OUTPUTS)),
        GET_STATE, 0,
        *do_step(0, STEP_10MS),
        SERIALIZE, 0, 0, 1, 3, 1, 1,  # into slot 1, unchanged
        SET_STATE, 1, 1,
        SERIALIZE, 0, 0, 1, 1, 1, 0,  # under the FMI 2.0 GUID
        SET_STATE, 0, 0, FREE_STATE, 0, 0, RESET, 0,
    ],
}


def main():
    out = here / "corpus" / "api_sequence_fmi3"
    out.mkdir(parents=True, exist_ok=True)
    for name, data in SEEDS.items():
        (out / f"seed-{name}").write_bytes(bytes(data))
    print(f"{len(SEEDS)} seeds in {out}")


if __name__ == "__main__":
    main()
