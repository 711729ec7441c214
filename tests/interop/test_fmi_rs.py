"""The Rust `fmi` crate as importer: interop-fmi-rs (a workspace member)
unzips the FMU with the crate, reads modelDescription.xml with its schema,
loads the binary and steps it on fmpy's grid (t_k = k * h), so its outputs
must equal fmpy's bit for bit.
"""

import json
import os
import subprocess

import numpy as np
import pytest
from fmpy.util import read_csv

import interop
from interop import EXPERIMENTS, OUTPUTS, REPO_ROOT

FMI_CRATE = "0.8.0"  # pinned in interop-fmi-rs/Cargo.toml
CARGO_TEST = ["cargo", "test", "--workspace", "--release"]  # as in tests/run_all.sh


@pytest.fixture(scope="session")
def fmi_rs():
    """The interop-fmi-rs executable: $TDVASS_INTEROP_FMI_RS, or cargo's.

    The `cargo test --workspace --release` step of tests/run_all.sh builds
    it for the crate's integration test; asking the same command for its
    artifacts rebuilds nothing, where `cargo build -p interop-fmi-rs` would
    resolve the dependencies' features differently and recompile some.
    Keep CARGO_TEST in step with run_all.sh.
    """
    override = os.environ.get("TDVASS_INTEROP_FMI_RS")
    if override:
        return override
    done = subprocess.run(
        CARGO_TEST + ["--no-run", "--message-format=json-render-diagnostics"],
        cwd=REPO_ROOT, capture_output=True, text=True,
    )
    assert done.returncode == 0, done.stderr
    for line in done.stdout.splitlines():
        message = json.loads(line)
        if (message.get("reason") == "compiler-artifact" and message["target"]["name"] == "interop-fmi-rs"
                and message["target"]["kind"] == ["bin"] and not message["profile"]["test"]):
            return message["executable"]
    pytest.fail("cargo built no interop-fmi-rs executable")


@pytest.mark.parametrize("name", list(EXPERIMENTS))
def test_fmi_crate_equals_fmpy(fmi_rs, fmu_file, fmpy_reference, tmp_path, name):
    experiment = json.loads(EXPERIMENTS[name].to_json())
    if name == "default":
        # Stop time and step from the DefaultExperiment, as the crate reads it.
        del experiment["stop_time"], experiment["step_size"]
    out = tmp_path / "out.csv"
    done = subprocess.run([fmi_rs, str(fmu_file), json.dumps(experiment), str(out)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert f"fmi {FMI_CRATE} loaded TDVASS (FMI 2.0" in done.stderr, done.stderr
    result = read_csv(str(out))
    times, reference = fmpy_reference(name)
    np.testing.assert_array_equal(result["time"], times)
    rows = np.column_stack([result[n] for n in OUTPUTS])
    agreed = interop.assert_agrees(rows, reference, what=f"fmi crate {name}")
    interop.record(f"fmi crate {FMI_CRATE}", name, "fmpy simulate_fmu", agreed)
