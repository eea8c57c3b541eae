"""Review of session 89's read-back of a file's diagnostics (`read_back`): a file whose
convergence record's ``flagged`` is no object (a string, a list, a number: the reader does not
check it, and `gpmsa info` prints such a record as it is) loaded before, its null R-hats as None;
`read_back` called ``flagged.get`` on it, so `gpmsa.load` and `gpmsa info` raised AttributeError.
Such a ``flagged`` names no element: its nulls read back as NaN."""

import math
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.fitting.emulator import Emulator
from gpmsa.io.container import read_raw
from gpmsa.mcmc import diagnostics

ODD_FLAGGED = ["R-hat inf", ["lamWOs"], 5, True]


@pytest.mark.parametrize("flagged", ODD_FLAGGED)
def test_read_back_ignores_a_flagged_record_that_is_no_object(flagged):
    summary = {"lamWOs": {"rhat": [None], "ess": [None, 2.0]}}
    out = diagnostics.read_back(summary, {"lamWOs": ()}, flagged)  # AttributeError before
    assert math.isnan(out["lamWOs"]["rhat"][0])
    assert math.isnan(out["lamWOs"]["ess"][0]) and out["lamWOs"]["ess"][1] == 2.0


@pytest.fixture(scope="module")
def held_file(tmp_path_factory):
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(8, 1)), rng.uniform(size=(8, 1))
    y = np.sin(3 * x[:, 0]) + t[:, 0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.GPMSAWarning)
        emu = gpmsa.fit(gpmsa.SimData(x=x, t=t, y=y[:, None]), n_iter=30, seed=1,
                        progress=False, tune=False, fixed={"lamWOs": 1000.0})  # fmt: skip
    return emu.save(tmp_path_factory.mktemp("review") / "e.gpmsa")


@pytest.mark.parametrize("flagged", ODD_FLAGGED)
def test_a_file_whose_flagged_record_is_no_object_still_loads(held_file, flagged):
    manifest, arrays = read_raw(held_file)
    assert manifest["diagnostics"]["lamWOs"]["rhat"] == [None]  # the held element: a null
    manifest["convergence"]["flagged"] = flagged
    loaded = Emulator.from_record(manifest, arrays)  # as gpmsa.load and gpmsa info build it
    assert math.isnan(loaded.diagnostics["lamWOs"]["rhat"][0])
    assert loaded.convergence["flagged"] == flagged  # kept as the file has it
