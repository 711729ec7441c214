"""The FMU libraries carry runtime code only: the writers of the model
descriptions and documentation (tdvass-describe) and quick-xml, which only
fmu-build links, must not be in any binary of either FMU.

Reads every library under binaries/ of both built FMUs (whatever platforms
they hold: the host's after `cargo run --release -p fmu-build`, all three
after `--all-platforms`)."""

import zipfile

import pytest
from conftest import FMU, FMU3

# Crates that only fmu-build may link, as their names appear in a binary
# (crate names in symbols and code-generation units, package names in
# paths of panic locations).
BUILD_TIME_ONLY = (b"quick_xml", b"quick-xml", b"tdvass_describe", b"tdvass-describe")


def build_time_code(binary: bytes) -> list[str]:
    """The names of build-time-only crates found in `binary`."""
    return [name.decode() for name in BUILD_TIME_ONLY if name in binary]


def libraries(fmu_path) -> dict[str, bytes]:
    """Every library of the FMU at `fmu_path`, by its entry name."""
    if not fmu_path.is_file():
        pytest.fail(f"{fmu_path} not found; build it with `cargo run --release -p fmu-build`")
    with zipfile.ZipFile(fmu_path) as fmu:
        return {name: fmu.read(name) for name in fmu.namelist()
                if name.startswith("binaries/") and not name.endswith("/")}


@pytest.mark.parametrize("fmu_path", [FMU, FMU3], ids=lambda p: p.name)
def test_no_library_carries_build_time_code(fmu_path):
    found = libraries(fmu_path)
    assert found, f"{fmu_path.name} holds no library"
    assert {name: build_time_code(binary) for name, binary in found.items()
            if build_time_code(binary)} == {}


def test_the_check_finds_quick_xml(tmp_path):
    """The check can fail: a library that names quick-xml's code-generation
    units, as one linking it does, is caught."""
    library = b"\x7fELF" + b"\0" * 64 + b"quick_xml.9aa2ce668b93b264-cgu.01\0" + b"\0" * 16
    assert build_time_code(library) == ["quick_xml"]
    fmu_path = tmp_path / "linked.fmu"
    with zipfile.ZipFile(fmu_path, "w") as fmu:
        fmu.writestr("binaries/linux64/tdvass.so", library)
        fmu.writestr("modelDescription.xml", "<fmiModelDescription/>")
    assert list(libraries(fmu_path)) == ["binaries/linux64/tdvass.so"]
    assert build_time_code(b"core/src/slice/sort/stable/quicksort.rs") == []
