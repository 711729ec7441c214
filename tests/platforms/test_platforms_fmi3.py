"""The FMI 3.0 binaries of tdvass-fmi3.fmu through harness_fmi3.c on every
platform: x86_64-linux natively, x86_64-windows under wine, aarch64-linux
under qemu. As for FMI 2.0 (test_platforms.py), every output at every
communication point, the FMU-state round trip and the outputs read inside
the intermediate-update callback must agree with the native run to 1e-12
relative; the serialized state is the same bytes everywhere."""

import pytest
from test_platforms import ALL_PLATFORMS, OTHER_PLATFORMS, SAVE_AT, after_save, compare

INTERMEDIATE_STEPS = 100  # harness_fmi3.c: steps run with the callback
STEP = 1e-3


@pytest.mark.parametrize("platform", OTHER_PLATFORMS)
@pytest.mark.parametrize("file", ["default.csv", "iso_c_cs.csv", "intermediate.csv", "model_exchange.csv"])
def test_fmi3_results_agree_with_linux64(results3, platform, file):
    compare(f"fmi3 {platform}", file, results3("linux64").table(file), results3(platform).table(file))


def test_fmi3_experiments_equal_the_fmi2_library(results, results3):
    """The FMI 3.0 and FMI 2.0 libraries come from one core: the same
    experiments (and the Model Exchange run) give the same outputs (header: the
    same value references)."""
    for file in ["default.csv", "iso_c_cs.csv", "model_exchange.csv"]:
        compare("fmi3 vs fmi2", file, results("linux64").table(file), results3("linux64").table(file))


def test_fmi3_experiments_differ_from_each_other(results3):
    header, default = results3("linux64").table("default.csv")
    _, iso = results3("linux64").table("iso_c_cs.csv")
    assert len(default) == len(iso) == 15001
    x_s = header.index("31")
    assert max(abs(row[x_s]) for row in default) > 1e-3
    assert [row[x_s] for row in default] != [row[x_s] for row in iso]


@pytest.mark.parametrize("platform", ALL_PLATFORMS)
def test_fmi3_state_round_trip_continues_the_run(results3, platform):
    run = results3(platform)
    continued = run.table("roundtrip.csv")
    assert continued[1] and continued[1][0][0] == pytest.approx(SAVE_AT + STEP)
    compare(f"fmi3 {platform}", "roundtrip.csv", after_save(results3("linux64").table("default.csv")), continued)
    compare(f"fmi3 {platform}", "roundtrip/own", after_save(run.table("default.csv")), continued)


@pytest.mark.parametrize("platform", ALL_PLATFORMS)
def test_fmi3_state_written_on_linux64_restores(results3, platform):
    restored = results3(platform).table("restored.csv")
    compare(f"fmi3 {platform}", "restored.csv", after_save(results3("linux64").table("default.csv")), restored)


@pytest.mark.parametrize("platform", OTHER_PLATFORMS)
def test_fmi3_serialized_state_is_the_same_bytes_on_every_platform(results3, platform):
    linux64 = results3("linux64").state()
    assert len(linux64) > 100
    assert results3(platform).state() == linux64


@pytest.mark.parametrize("platform", ALL_PLATFORMS)
def test_fmi3_intermediate_update_reads_outputs_inside_the_steps(results3, platform):
    """The callback is called at internal nodes strictly inside the
    communication steps, in order, and what it reads moves."""
    header, rows = results3(platform).table("intermediate.csv")
    times = [row[0] for row in rows]
    assert len(rows) >= INTERMEDIATE_STEPS, len(rows)
    assert all(a < b for a, b in zip(times, times[1:]))
    assert 0.0 < times[0] and times[-1] <= INTERMEDIATE_STEPS * STEP + 1e-12
    x_s = header.index("31")
    assert len({row[x_s] for row in rows}) == len(rows)

