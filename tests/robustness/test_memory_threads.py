"""valgrind memcheck over 10 000 life cycles, and 8 threads stepping their
own instances concurrently, both through the C harness (harness.c) built
with gcc against the real shared library."""

import os
import re
import shutil
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

import fmi2

HERE = Path(__file__).resolve().parent
CYCLES = int(os.environ.get("TDVASS_VALGRIND_CYCLES", "10000"))


@pytest.fixture(scope="module")
def harness(tmp_path_factory):
    if not shutil.which("gcc"):
        pytest.fail("gcc is needed to build tests/robustness/harness.c")
    out = tmp_path_factory.mktemp("harness") / "harness"
    subprocess.run(["gcc", "-O1", "-g", "-Wall", "-Wextra", "-Werror", "-pthread", "-o", str(out),
                    str(HERE / "harness.c"), "-ldl"], check=True)
    return out


def run(harness, lib, *args, prefix=(), timeout=900):
    return subprocess.run([*prefix, str(harness), str(lib._name), fmi2.guid(), *args], capture_output=True,
                          text=True, timeout=timeout)


def test_threads_are_bit_identical_to_a_serial_run(harness, lib):
    done = run(harness, lib, "threads", "8")
    assert done.returncode == 0, done.stderr
    assert "8 threads x 2 instances x 4000 steps, bit-identical to the serial run" in done.stdout


def test_cycles_run_natively(harness, lib):
    done = run(harness, lib, "cycles", "200")
    assert done.returncode == 0, done.stderr
    assert "cycles: 200 completed" in done.stdout


def test_valgrind_memcheck_over_10000_cycles(harness, lib):
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
        results = list(pool.map(lambda n: run(harness, lib, "cycles", str(n), prefix=memcheck), parts))
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
        print(f"valgrind, {n} cycles:\n{summary}")
