"""Every Linux library of the FMUs (the quarter car's, the corner's and the
chassis's, and the FMI 2.0 aarch64 library the platform tests run) loads on
glibc 2.17 and needs only system libraries: the policy of elf_policy.py. The
highest GLIBC version and the NEEDED list of each library are printed at the
end of the run. The corner's and the chassis's FMUs carry the very libraries
of the quarter car's FMU of the same FMI version."""

import subprocess
import zipfile

import pytest
from conftest import CHASSIS, CHASSIS3, CORNER, CORNER3, FMU, FMU3, ELF_POLICY, require_tool, target_dir
from elf_policy import GLIBC_FLOOR, SYSTEM_LIBRARIES, check, check_fmu, show

AARCH64_FMI2 = target_dir() / "aarch64-unknown-linux-gnu" / "release" / "libtdvass_fmi2.so"

# The Linux libraries each FMU must carry: none may escape the check.
EXPECTED = {
    "tdvass.fmu": ["binaries/linux64/tdvass.so"],
    "tdvass-fmi3.fmu": ["binaries/aarch64-linux/tdvass.so", "binaries/x86_64-linux/tdvass.so"],
    "tdvass-corner.fmu": ["binaries/linux64/tdvass.so"],
    "tdvass-corner-fmi3.fmu": ["binaries/aarch64-linux/tdvass.so", "binaries/x86_64-linux/tdvass.so"],
    "tdvass-chassis.fmu": ["binaries/linux64/tdvass.so"],
    "tdvass-chassis-fmi3.fmu": ["binaries/aarch64-linux/tdvass.so", "binaries/x86_64-linux/tdvass.so"],
}


@pytest.fixture(scope="module")
def reports():
    require_tool("readelf", "binutils")
    found = []
    for fmu in (FMU, FMU3, CORNER, CORNER3, CHASSIS, CHASSIS3):
        if not fmu.is_file():
            pytest.fail(f"{fmu} not found; build it with `cargo run --release -p fmu-build -- --all-platforms`")
        found += check_fmu(fmu)
    if not AARCH64_FMI2.is_file():
        pytest.fail(f"{AARCH64_FMI2} not found; build it with `cargo run --release -p fmu-build -- --all-platforms`")
    found.append(check(AARCH64_FMI2, "target/aarch64-unknown-linux-gnu/release/libtdvass_fmi2.so"))
    ELF_POLICY[:] = [r.summary() for r in found]
    return found


def test_every_linux_library_of_the_fmus_is_checked(reports):
    names = sorted(r.name for r in reports)
    expected = sorted(f"{fmu}:{entry}" for fmu, entries in EXPECTED.items() for entry in entries)
    assert names == sorted(expected + ["target/aarch64-unknown-linux-gnu/release/libtdvass_fmi2.so"])
    machines = {r.name: r.machine for r in reports}
    assert machines["tdvass.fmu:binaries/linux64/tdvass.so"] == "X86-64"
    assert machines["tdvass-fmi3.fmu:binaries/aarch64-linux/tdvass.so"] == "AArch64"
    assert machines["tdvass-corner.fmu:binaries/linux64/tdvass.so"] == "X86-64"
    assert machines["tdvass-corner-fmi3.fmu:binaries/aarch64-linux/tdvass.so"] == "AArch64"
    assert machines["tdvass-chassis.fmu:binaries/linux64/tdvass.so"] == "X86-64"
    assert machines["tdvass-chassis-fmi3.fmu:binaries/aarch64-linux/tdvass.so"] == "AArch64"


def binaries(fmu):
    with zipfile.ZipFile(fmu) as z:
        return {name: z.read(name) for name in z.namelist() if name.startswith("binaries/") and not name.endswith("/")}


def test_the_corner_and_the_chassis_carry_the_quarter_cars_libraries(reports):
    """Each version's library is built once and carried by all three
    models' FMUs: every binary of a corner or chassis FMU (Windows too) is
    byte for byte the quarter car's of the same version, and none lacks one."""
    for quarter_car, other in [(FMU, CORNER), (FMU3, CORNER3), (FMU, CHASSIS), (FMU3, CHASSIS3)]:
        ours, theirs = binaries(other), binaries(quarter_car)
        assert sorted(ours) == sorted(theirs), (other.name, sorted(ours), sorted(theirs))
        assert len(ours) >= 2, (other.name, sorted(ours))  # a Linux and a Windows library at least
        for name in ours:
            assert ours[name] == theirs[name], (other.name, name)


def test_highest_glibc_version_is_at_most_2_17(reports):
    for report in reports:
        assert report.highest_glibc is not None, report.summary()
        assert report.highest_glibc <= GLIBC_FLOOR, report.summary()


def test_needed_lists_only_system_libraries(reports):
    for report in reports:
        assert report.needed, report.summary()
        assert "libc.so.6" in report.needed, report.summary()
        assert set(report.needed) <= SYSTEM_LIBRARIES | {"ld-linux-x86-64.so.2", "ld-linux-aarch64.so.1"}, \
            report.summary()


def test_no_library_breaks_the_policy(reports):
    assert [r.summary() for r in reports if r.violations] == []


def test_the_policy_rejects_a_library_linked_against_this_machines_glibc(tmp_path):
    """The check can fail: a library built here with the host's gcc against
    Debian's glibc (reallocarray is GLIBC_2.26) and linked to libstdc++ is
    refused on both counts."""
    gcc = require_tool("gcc", "gcc")
    source = tmp_path / "newer.c"
    source.write_text("#include <stdlib.h>\n"
                      "void *grow(void *p, size_t n) { return reallocarray(p, n, 16); }\n")
    library = tmp_path / "libnewer.so"
    subprocess.run([gcc, "-shared", "-fPIC", "-O2", "-o", str(library), str(source),
                    "-Wl,--no-as-needed", "-lstdc++"], check=True, capture_output=True)
    report = check(library)
    assert report.highest_glibc is not None and report.highest_glibc > GLIBC_FLOOR, report.summary()
    assert any("GLIBC_2.26" in v and "reallocarray" in v for v in report.violations), report.summary()
    assert any("NEEDED libstdc++.so.6" in v for v in report.violations), report.summary()
    assert f"newer than GLIBC_{show(GLIBC_FLOOR)}" in report.summary()
