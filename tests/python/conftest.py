"""Fixtures for the fmpy tests of the built FMUs (target/fmu/tdvass.fmu, the
corner's tdvass-corner.fmu and tdvass-corner-fmi3.fmu, and the chassis's
tdvass-chassis.fmu and tdvass-chassis-fmi3.fmu).

Nothing is built here: run `cargo run --release -p fmu-build` first.
"""

import sys
from pathlib import Path

import pytest
from fmpy import extract, read_model_description

sys.path.insert(0, str(Path(__file__).resolve().parent))

from fmu_helpers import (  # noqa: E402
    Slave,
    chassis_fmi3_path,
    chassis_path,
    corner_fmi3_path,
    corner_path,
    fmu_path,
)


@pytest.fixture(scope="session")
def fmu_file() -> Path:
    path = fmu_path()
    if not path.is_file():
        pytest.fail(f"{path} not found; build it with `cargo run --release -p fmu-build`")
    return path


def built(path: Path) -> Path:
    if not path.is_file():
        pytest.fail(f"{path} not found; build it with `cargo run --release -p fmu-build`")
    return path


@pytest.fixture(scope="session")
def corner_file() -> Path:
    """The corner's FMI 2.0 FMU (Co-Simulation)."""
    return built(corner_path())


@pytest.fixture(scope="session")
def corner_fmi3_file() -> Path:
    """The corner's FMI 3.0 FMU (Co-Simulation)."""
    return built(corner_fmi3_path())


@pytest.fixture(scope="session")
def chassis_file() -> Path:
    """The chassis's FMI 2.0 FMU (Co-Simulation)."""
    return built(chassis_path())


@pytest.fixture(scope="session")
def chassis_fmi3_file() -> Path:
    """The chassis's FMI 3.0 FMU (Co-Simulation)."""
    return built(chassis_fmi3_path())


@pytest.fixture(scope="session")
def model_description(fmu_file):
    return read_model_description(str(fmu_file))


@pytest.fixture(scope="session")
def unzipdir(fmu_file, tmp_path_factory):
    return Path(extract(str(fmu_file), unzipdir=str(tmp_path_factory.mktemp("fmu"))))


@pytest.fixture
def make_slave(unzipdir, model_description):
    """Factory of instances, all freed at the end of the test."""
    made = []

    def make(name="tdvass", **kwargs):
        slave = Slave(unzipdir, model_description, name=name, **kwargs)
        made.append(slave)
        return slave

    yield make
    for slave in made:
        slave.free()
