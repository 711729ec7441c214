"""The shipped binaries themselves: what the FMU holds, which DLLs the
Windows library imports, what every library exports, and that fmpy accepts
the multi-platform FMU."""

import re
import subprocess
import sys
from pathlib import Path

from conftest import FMU, require_tool
from elf_policy import SYSTEM_LIBRARIES

# Every DLL that binaries/win64/tdvass.dll imports, lower-cased. All ship with
# a stock Windows 10 (api-ms-win-core-synch-l1-2-0 is an API set of Windows 8
# and later; bcryptprimitives.dll has ProcessPrng since Windows 10). The MinGW
# runtime (libgcc_s_seh-1.dll, libwinpthread-1.dll) is linked statically
# (.cargo/config.toml) and must never appear here.
EXPECTED_DLL_IMPORTS = {
    "api-ms-win-core-synch-l1-2-0.dll",
    "bcryptprimitives.dll",
    "kernel32.dll",
    "msvcrt.dll",
    "ntdll.dll",
    "userenv.dll",
    "ws2_32.dll",
}
MINGW_RUNTIME = {"libgcc_s_seh-1.dll", "libwinpthread-1.dll", "libstdc++-6.dll"}

# Shared objects the Linux libraries may link to: the system libraries of
# the glibc 2.17 policy (elf_policy.py, checked in full by
# test_elf_policy.py), present on every glibc system.
EXPECTED_ELF_NEEDED = SYSTEM_LIBRARIES


def objdump(tool: str, package: str, *args) -> str:
    return subprocess.run([require_tool(tool, package), *args], check=True, capture_output=True,
                          text=True).stdout


def dll_imports(path: Path) -> set[str]:
    text = objdump("x86_64-w64-mingw32-objdump", "binutils-mingw-w64-x86-64", "-p", str(path))
    return {name.lower() for name in re.findall(r"DLL Name: (\S+)", text)}


def dll_exports(path: Path) -> set[str]:
    text = objdump("x86_64-w64-mingw32-objdump", "binutils-mingw-w64-x86-64", "-p", str(path))
    table = text.split("[Ordinal/Name Pointer] Table", 1)[1]
    return set(re.findall(r"^\s+\[\s*\d+\]\s+(\S+)$", table, re.M))


def elf_exports(tool: str, package: str, path: Path) -> set[str]:
    text = objdump(tool, package, "-T", str(path))
    return {line.split()[-1] for line in text.splitlines()
            if " .text" in line and line.split()[-1].startswith("fmi2")}


def elf_needed(tool: str, package: str, path: Path) -> set[str]:
    text = objdump(tool, package, "-p", str(path))
    return set(re.findall(r"NEEDED\s+(\S+)", text))


def debug_sections(tool: str, package: str, path: Path) -> list[str]:
    text = objdump(tool, package, "-h", str(path))
    return re.findall(r"\s(\.z?debug\S*)", text)


def test_fmu_holds_linux64_and_win64_and_nothing_for_tests(fmu):
    assert sorted(fmu.namelist()) == [
        "binaries/linux64/tdvass.so",
        "binaries/win64/tdvass.dll",
        "documentation/diagram.png",
        "documentation/index.html",
        "extra/org.fmi-standard.fmi-ls-ref/fmi-ls-manifest.xml",
        "extra/org.fmi-standard.fmi-ls-ref/tdvass_out.csv",
        "model.png",
        "modelDescription.xml",
    ]


def test_windows_dll_imports_only_system_dlls(platforms):
    imports = dll_imports(platforms["win64"].library)
    assert not imports & MINGW_RUNTIME, f"the MinGW runtime is linked dynamically: {imports & MINGW_RUNTIME}"
    assert imports == EXPECTED_DLL_IMPORTS


def test_linux_libraries_need_only_the_c_runtime(platforms):
    assert elf_needed("objdump", "binutils", platforms["linux64"].library) <= EXPECTED_ELF_NEEDED | {
        "ld-linux-x86-64.so.2"}
    assert elf_needed("aarch64-linux-gnu-objdump", "binutils-aarch64-linux-gnu",
                      platforms["aarch64"].library) <= EXPECTED_ELF_NEEDED | {"ld-linux-aarch64.so.1"}


def test_every_platform_exports_the_same_fmi2_functions(platforms):
    linux64 = elf_exports("objdump", "binutils", platforms["linux64"].library)
    assert {"fmi2Instantiate", "fmi2DoStep", "fmi2DeSerializeFMUstate", "fmi2GetTypesPlatform"} <= linux64
    assert {e for e in dll_exports(platforms["win64"].library) if e.startswith("fmi2")} == linux64
    assert elf_exports("aarch64-linux-gnu-objdump", "binutils-aarch64-linux-gnu",
                       platforms["aarch64"].library) == linux64


def test_shipped_libraries_carry_no_debug_info(platforms):
    assert debug_sections("objdump", "binutils", platforms["linux64"].library) == []
    assert debug_sections("x86_64-w64-mingw32-objdump", "binutils-mingw-w64-x86-64",
                          platforms["win64"].library) == []
    assert debug_sections("aarch64-linux-gnu-objdump", "binutils-aarch64-linux-gnu",
                          platforms["aarch64"].library) == []


def test_windows_dll_carries_no_symbol_table(platforms):
    """Stripped (.cargo/config.toml); the exported functions remain."""
    text = objdump("x86_64-w64-mingw32-objdump", "binutils-mingw-w64-x86-64", "-t",
                   str(platforms["win64"].library))
    assert "no symbols" in text


def fmpy(*args) -> str:
    fmpy_script = Path(sys.executable).parent / "fmpy"
    result = subprocess.run([str(fmpy_script), *args], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr
    return result.stdout


def test_fmpy_validate_finds_no_problem():
    assert fmpy("validate", str(FMU)).strip() == "No problems found."


def test_fmpy_info_lists_both_platforms():
    platforms = re.search(r"^\s*Platforms\s+(.+)$", fmpy("info", str(FMU)), re.M)
    assert platforms, "fmpy info printed no Platforms line"
    assert sorted(p.strip() for p in platforms.group(1).split(",")) == ["linux64", "win64"]
    import fmpy as fmpy_module

    assert sorted(fmpy_module.supported_platforms(str(FMU))) == ["linux64", "win64"]


def test_fmpy_simulates_the_fmu_on_this_host():
    """fmpy on this host picks linux64 out of the multi-platform FMU (the
    win64 binary beside it changes nothing for a Linux importer)."""
    from fmpy import simulate_fmu

    result = simulate_fmu(str(FMU), stop_time=0.1, output_interval=0.01, output=["x_s"])
    assert len(result) == 11 and abs(result["x_s"][-1]) > 0.0
