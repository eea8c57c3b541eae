"""An emulator file whose precision is subnormal (its variance 1 / lam overflows float64) is
refused by the file checks naming the array (session 84), as `Emulator` refuses it in params.
Before: the checks passed it and the constructor's message named ``params['lamUz']``, not the
file's field (a hypothesis draw of tests/gpmsa/test_file_hostile.py found it under another
hypothesis version)."""

import numpy as np
import pytest

import gpmsa
from gpmsa.io.container import ENVELOPE, read_raw, write_raw


@pytest.mark.parametrize("name", ["param_lamUz", "param_lamWs", "param_lamWOs"])
def test_a_subnormal_precision_in_a_file_names_its_array(tmp_path, name):
    rng = np.random.default_rng(1)
    x, t = rng.random((14, 1)), rng.random((14, 1))
    sim = gpmsa.SimData(x=x, t=t, y=(1.0 + t) * np.sin(np.pi * x) + 0.3 * t)
    params = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [5000.0], "lamWOs": [5000.0]}
    path = gpmsa.Emulator.from_params(sim, params).save(tmp_path / "e.gpmsa")
    manifest, arrays = read_raw(path)
    arrays[name] = np.array([5e-324])
    write_raw(path, {k: v for k, v in manifest.items() if k not in ENVELOPE}, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match=rf"arrays/{name}: holds 5e-324 .*overflows"):
        gpmsa.load(path)
