"""The Rust `fmi` crate as importer: interop-fmi-rs (a workspace member)
unzips the FMU with the crate, reads modelDescription.xml with its schema,
loads the binary and steps it on fmpy's grid (t_k = k * h), so its outputs
must equal fmpy's bit for bit.
"""

import json
import subprocess

import numpy as np
import pytest
from fmpy.util import read_csv

import interop
from interop import EXPERIMENTS, OUTPUTS

from conftest import FMI_CRATE


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
