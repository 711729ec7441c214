"""valgrind memcheck over FMI 3.0 life cycles (with intermediate updates,
early return, Configuration Mode, arrays and FMU states) through the C
harness harness_fmi3.c, built with gcc against the real shared library."""

import os
import re
import shutil
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

import fmi3

HERE = Path(__file__).resolve().parent
CYCLES = int(os.environ.get("TDVASS_VALGRIND_FMI3_CYCLES", "2000"))
NAMES = ["variant", "road", "root_count", "rightmost_roots", "max_internal_step", "intermediate_update_interval",
         "x_g", "m_s", "x_s", "objective"]


@pytest.fixture(scope="module")
def harness(tmp_path_factory):
    if not shutil.which("gcc"):
        pytest.fail("gcc is needed to build tests/robustness/harness_fmi3.c")
    out = tmp_path_factory.mktemp("harness") / "harness_fmi3"
    subprocess.run(["gcc", "-O1", "-g", "-Wall", "-Wextra", "-Werror", "-o", str(out),
                    str(HERE / "harness_fmi3.c"), "-ldl"], check=True)
    return out


def run(harness, lib3, n, prefix=(), timeout=900):
    variables = fmi3.variables()
    references = [f"{name}={variables[name][0]}" for name in NAMES]
    return subprocess.run([*prefix, str(harness), str(lib3._name), fmi3.instantiation_token(), "cycles", str(n),
                           *references], capture_output=True, text=True, timeout=timeout)


def test_cycles_run_natively(harness, lib3):
    done = run(harness, lib3, 200)
    assert done.returncode == 0, done.stderr
    assert "cycles: 200 completed" in done.stdout


def test_a_wrong_token_fails_the_harness(harness, lib3, tmp_path):
    """The harness notices a failure (instantiation refused)."""
    done = subprocess.run([str(harness), str(lib3._name), "{wrong}", "cycles", "1",
                           *[f"{n}={fmi3.variables()[n][0]}" for n in NAMES]], capture_output=True, text=True)
    assert done.returncode == 1 and "instantiate failed in cycle 0" in done.stderr


def test_valgrind_memcheck_over_fmi3_cycles(harness, lib3):
    """0 bytes definitely or indirectly lost, no invalid access. The cycles
    are split over two processes (the machine has two cores)."""
    if not shutil.which("valgrind"):
        if os.environ.get("CI"):
            pytest.fail("valgrind is missing (.ci/run installs it)")
        pytest.skip("valgrind is not installed")
    memcheck = ("valgrind", "--tool=memcheck", "--leak-check=full", "--show-leak-kinds=definite,indirect",
                "--errors-for-leak-kinds=definite,indirect", "--error-exitcode=99")
    parts = [CYCLES // 2, CYCLES - CYCLES // 2]
    with ThreadPoolExecutor(len(parts)) as pool:
        results = list(pool.map(lambda n: run(harness, lib3, n, prefix=memcheck), parts))
    for n, done in zip(parts, results):
        report = done.stderr
        assert done.returncode == 0, report[-4000:]
        assert f"cycles: {n} completed" in done.stdout
        assert re.search(r"ERROR SUMMARY: 0 errors from 0 contexts", report), report[-4000:]
        assert "Invalid read" not in report and "Invalid write" not in report
        for kind in ("definitely lost", "indirectly lost"):
            m = re.search(rf"{kind}: ([\d,]+) bytes", report)
            assert m is None or m.group(1) == "0", report[-4000:]
        assert ("definitely lost: 0 bytes" in report) or ("no leaks are possible" in report), report[-4000:]
        summary = "\n".join(line for line in report.splitlines() if "lost:" in line or "SUMMARY" in line)
        print(f"valgrind, FMI 3.0, {n} cycles:\n{summary}")
