"""The policy every Linux library of the FMUs must meet, in the manner of
auditwheel's manylinux2014 check: it loads on any Linux with glibc 2.17 or
newer and needs nothing but the system's own libraries.

- Every symbol version the library needs (its `.gnu.version_r`, as
  `readelf -V` prints it) is `GLIBC_x.y[.z]` at most 2.17, or `GCC_x.y[.z]`
  (libgcc_s) at most 4.8.0. GLIBC_PRIVATE and every other version family
  fail.
- `NEEDED` names only libc, libm, libpthread, libdl, librt, libgcc_s and the
  platform's dynamic loader.

    python tests/platforms/elf_policy.py [LIBRARY_OR_FMU ...]

prints each library's highest GLIBC version (with the symbols that need
it) and its NEEDED list, and exits with 1 if one breaks the policy. Without
arguments it checks both FMUs in <target>/fmu and the FMI 2.0 aarch64
library (test_elf_policy.py runs the same check).
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

GLIBC_FLOOR = (2, 17)
GCC_FLOOR = (4, 8, 0)
SYSTEM_LIBRARIES = {"libc.so.6", "libm.so.6", "libpthread.so.0", "libdl.so.2", "librt.so.1", "libgcc_s.so.1"}
LOADERS = {"X86-64": "ld-linux-x86-64.so.2", "AArch64": "ld-linux-aarch64.so.1"}

VERSION_NEED_FILE = re.compile(r"^\s*(?:0x)?[0-9a-f]+: Version: \d+\s+File: (\S+)\s+Cnt: \d+")
VERSION_NEED_NAME = re.compile(r"^\s*(?:0x)?[0-9a-f]+:\s+Name: (\S+)\s+Flags:")
VERSIONED_SYMBOL = re.compile(r"\s(\S+)@(GLIBC_[0-9.]+)\s")
NEEDED = re.compile(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]")
MACHINE = re.compile(r"^\s*Machine:\s+(.+)$", re.M)


def readelf(*args: str) -> str:
    return subprocess.run(["readelf", "-W", *args], check=True, capture_output=True, text=True).stdout


def version_tuple(name: str, family: str) -> tuple[int, ...] | None:
    match = re.fullmatch(rf"{family}_(\d+(?:\.\d+)*)", name)
    return tuple(int(part) for part in match.group(1).split(".")) if match else None


def show(version: tuple[int, ...]) -> str:
    return ".".join(map(str, version))


@dataclass
class Report:
    """What one library needs, and where it breaks the policy."""

    name: str
    machine: str
    needed: list[str]
    # (version name, the file it is needed from), as readelf -V lists them
    version_needs: list[tuple[str, str]]
    # GLIBC version name -> the undefined symbols bound to it
    glibc_symbols: dict[str, list[str]]
    violations: list[str] = field(default_factory=list)

    @property
    def highest_glibc(self) -> tuple[int, ...] | None:
        versions = [v for v in (version_tuple(n, "GLIBC") for n, _ in self.version_needs) if v]
        return max(versions) if versions else None

    def summary(self) -> str:
        highest = self.highest_glibc
        symbols = self.glibc_symbols.get(f"GLIBC_{show(highest)}", []) if highest else []
        shown = ", ".join(symbols[:6]) + (", ..." if len(symbols) > 6 else "")
        verdict = "ok" if not self.violations else "FAILS: " + "; ".join(self.violations)
        return (f"{self.name} ({self.machine}): highest GLIBC_{show(highest) if highest else '-'}"
                f"{f' ({shown})' if shown else ''}; NEEDED {', '.join(self.needed)}; {verdict}")


def check(path: Path, name: str | None = None) -> Report:
    """The policy report of the ELF shared object at `path`."""
    header = readelf("-h", str(path))
    machine_match = MACHINE.search(header)
    machine = machine_match.group(1).strip() if machine_match else "unknown"
    machine = {"Advanced Micro Devices X86-64": "X86-64"}.get(machine, machine)
    needed = NEEDED.findall(readelf("-d", str(path)))
    versions_text = readelf("-V", str(path))
    needs_section = versions_text.split("Version needs section", 1)
    version_needs: list[tuple[str, str]] = []
    if len(needs_section) == 2:
        current = "?"
        for line in needs_section[1].splitlines():
            file_match = VERSION_NEED_FILE.match(line)
            if file_match:
                current = file_match.group(1)
                continue
            name_match = VERSION_NEED_NAME.match(line)
            if name_match:
                version_needs.append((name_match.group(1), current))
    glibc_symbols: dict[str, list[str]] = {}
    for line in readelf("--dyn-syms", str(path)).splitlines():
        if " UND " not in line:
            continue
        match = VERSIONED_SYMBOL.search(line + " ")
        if match:
            glibc_symbols.setdefault(match.group(2), []).append(match.group(1))
    report = Report(name or str(path), machine, needed, version_needs, glibc_symbols)

    loader = LOADERS.get(machine)
    if loader is None:
        report.violations.append(f"machine {machine} is not a Linux platform of the FMUs")
    for library in needed:
        if library not in SYSTEM_LIBRARIES and library != loader:
            report.violations.append(f"NEEDED {library} is not a system library")
    for version, source in version_needs:
        glibc = version_tuple(version, "GLIBC")
        gcc = version_tuple(version, "GCC")
        if glibc is not None:
            if glibc > GLIBC_FLOOR:
                symbols = ", ".join(glibc_symbols.get(version, [])) or "?"
                report.violations.append(f"{version} from {source} ({symbols}) is newer than "
                                         f"GLIBC_{show(GLIBC_FLOOR)}")
        elif gcc is not None:
            if gcc > GCC_FLOOR:
                report.violations.append(f"{version} from {source} is newer than GCC_{show(GCC_FLOOR)}")
        else:
            report.violations.append(f"symbol version {version} from {source} is not allowed")
    if not version_needs:
        report.violations.append("no symbol versions needed at all: not a glibc-linked library?")
    return report


def linux_libraries(fmu: Path) -> dict[str, bytes]:
    """Every ELF file under binaries/ of `fmu`: entry name -> bytes."""
    with zipfile.ZipFile(fmu) as archive:
        return {name: archive.read(name) for name in archive.namelist()
                if name.startswith("binaries/") and archive.read(name)[:4] == b"\x7fELF"}


def check_fmu(fmu: Path) -> list[Report]:
    reports = []
    with tempfile.TemporaryDirectory() as scratch:
        for entry, content in sorted(linux_libraries(fmu).items()):
            path = Path(scratch) / entry.replace("/", "_")
            path.write_bytes(content)
            reports.append(check(path, f"{fmu.name}:{entry}"))
    return reports


def default_libraries() -> list[Path]:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from conftest import CORNER, CORNER3, FMU, FMU3, target_dir

    return [FMU, FMU3, CORNER, CORNER3,
            target_dir() / "aarch64-unknown-linux-gnu" / "release" / "libtdvass_fmi2.so"]


def main(argv: list[str]) -> int:
    paths = [Path(a) for a in argv[1:]] or default_libraries()
    reports = []
    for path in paths:
        reports += check_fmu(path) if path.suffix == ".fmu" else [check(path)]
    for report in reports:
        print(report.summary())
    return 1 if any(r.violations for r in reports) else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
