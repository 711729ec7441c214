"""Fixtures of the robustness suite: the real shared library through ctypes.

The libraries are taken from the built FMUs (see fmi2.py and fmi3.py);
build them first with `cargo run --release -p fmu-build`.
"""

import sys
from decimal import Decimal
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

import fmi2  # noqa: E402
import fmi3  # noqa: E402


@pytest.fixture(scope="session")
def lib():
    try:
        return fmi2.load()
    except FileNotFoundError as e:
        pytest.fail(str(e))


@pytest.fixture
def make(lib):
    """Factory of instances, all freed at the end of the test (which also
    checks that freeing works in whatever state the test left them)."""
    made = []

    def new(**kwargs):
        inst = fmi2.Instance(lib, **kwargs)
        made.append(inst)
        return inst

    yield new
    for inst in made:
        inst.free()
    # The process is alive and the library still answers.
    assert lib.fmi2GetVersion() == b"2.0"


def rust(value: float) -> str:
    """`value` as Rust's `{}` prints an f64 (how the FMU names values)."""
    if value != value:
        return "NaN"
    if value in (float("inf"), float("-inf")):
        return "inf" if value > 0 else "-inf"
    text = format(Decimal(repr(value)), "f")
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return text


@pytest.fixture
def initialized(make):
    """An instance in stepComplete at t = 0 (default experiment, stop 15 s)."""

    def new(stop=15.0, **values):
        inst = make()
        inst.initialize(stop=stop, **values)
        return inst

    return new


# ------------------------------------------------------------------ FMI 3.0


@pytest.fixture(scope="session")
def lib3():
    try:
        return fmi3.load()
    except FileNotFoundError as e:
        pytest.fail(str(e))


@pytest.fixture
def make3(lib3):
    """Factory of FMI 3.0 instances, all freed at the end of the test (which
    also checks that freeing works in whatever state the test left them)."""
    made = []

    def new(**kwargs):
        inst = fmi3.Instance(lib3, **kwargs)
        made.append(inst)
        return inst

    yield new
    for inst in made:
        inst.free()
    # The process is alive and the library still answers.
    assert lib3.fmi3GetVersion() == b"3.0"


@pytest.fixture
def initialized3(make3):
    """An FMI 3.0 instance in Step Mode at t = 0 (default experiment, stop 15 s)."""

    def new(stop=15.0, instance=None, **values):
        inst = make3(**(instance or {}))
        inst.initialize(stop=stop, **values)
        return inst

    return new


# ----------------------------------------------------------- Model Exchange


@pytest.fixture
def model_exchange(make):
    """An FMI 2.0 Model Exchange instance in eventMode at t = 0 (stop 15 s)."""

    def new(stop=15.0, **values):
        inst = make(fmu_type=fmi2.MODEL_EXCHANGE)
        inst.initialize_model_exchange(stop=stop, **values)
        return inst

    return new


@pytest.fixture
def model_exchange3(make3):
    """An FMI 3.0 Model Exchange instance in Event Mode at t = 0 (stop 15 s)."""

    def new(stop=15.0, **values):
        inst = make3(model_exchange=True)
        inst.initialize_model_exchange(stop=stop, **values)
        return inst

    return new
