"""A loaded emulator's diagnostics read as the fitted one's: the file's JSON stores NaN and inf as
null, and `gpmsa.load` gave those back as None (`np.nanmin(emu.diagnostics["lamWOs"]["ess"])`
worked on the fitted emulator and raised TypeError on the loaded one; an infinite R-hat, chains
stuck apart, read None where ``rhat > 1.01`` must hold). A null inside a list now comes back as
NaN, and as inf for an R-hat the convergence record calls infinite."""

import math
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.mcmc import diagnostics


@pytest.fixture(scope="module")
def held_fit():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 1))
    y = np.sin(3 * x[:, 0]) + t[:, 0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.fit(gpmsa.SimData(x=x, t=t, y=y[:, None]), n_iter=60, seed=1,
                         progress=False, fixed={"lamWOs": 1000.0})  # fmt: skip


def same(a, b) -> bool:
    """Equal, NaN equal to NaN (lists and dicts walked)."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(map(same, a, b))
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (math.isnan(a) and math.isnan(b))
    return a == b and type(a) is type(b)


def test_a_held_parameters_nan_diagnostics_come_back_nan(held_fit, tmp_path):
    assert math.isnan(held_fit.diagnostics["lamWOs"]["ess"][0])  # the case: a held element
    held_fit.save(tmp_path / "e.gpmsa")
    loaded = gpmsa.load(tmp_path / "e.gpmsa")
    assert same(held_fit.diagnostics, loaded.diagnostics)  # [None] before
    assert math.isnan(loaded.diagnostics["lamWOs"]["ess"][0] + 1.0)  # TypeError before
    assert same(held_fit.convergence, loaded.convergence)


def test_an_infinite_rhat_comes_back_infinite_and_other_nulls_nan():
    summary = {
        "lamUz": {"mean": [1.0, 2.0], "rhat": [None, None], "ess": [None, 3.0],
                  "accept": [None, 0.5]},
        "lamWs": {"accept": None, "rhat": [1.0]},
    }  # fmt: skip
    flagged = {"lamUz[1]": diagnostics.INFINITE_RHAT + ", ESS 3 < 100",
               "lamUz[0]": "constant draws (no proposal accepted)"}  # fmt: skip
    out = diagnostics.read_back(summary, {"lamUz": (2,), "lamWs": (1,)}, flagged)
    assert math.isnan(out["lamUz"]["rhat"][0]) and out["lamUz"]["rhat"][1] == math.inf
    assert math.isnan(out["lamUz"]["ess"][0]) and out["lamUz"]["ess"][1] == 3.0
    assert math.isnan(out["lamUz"]["accept"][0]) and out["lamUz"]["accept"][1] == 0.5
    assert out["lamWs"] == {"accept": None, "rhat": [1.0]}  # a field stored whole as null
    assert summary["lamUz"]["rhat"] == [None, None]  # the input is not changed


def test_an_emulator_whose_chains_stick_apart_reads_an_infinite_rhat_after_loading(tmp_path):
    rng = np.random.default_rng(3)
    x, t = rng.uniform(size=(10, 1)), rng.uniform(size=(10, 1))
    y = np.cos(2 * x[:, 0]) - t[:, 0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        emu = gpmsa.fit(gpmsa.SimData(x=x, t=t, y=y[:, None]), n_iter=40, seed=2,
                        progress=False, n_chains=2)  # fmt: skip
    # chains stuck apart, as a file of such a fit records them: each constant, values differ
    rh = emu.diagnostics["lamWs"]["rhat"]
    emu.diagnostics["lamWs"]["rhat"] = [math.inf] * len(rh)
    emu.convergence["rhat"]["lamWs"] = [math.inf] * len(rh)
    for el in diagnostics.element_names("lamWs", emu.draws["lamWs"].shape[1:]):
        emu.convergence["flagged"][el] = diagnostics.INFINITE_RHAT
    emu.save(tmp_path / "e.gpmsa")
    loaded = gpmsa.load(tmp_path / "e.gpmsa")
    assert loaded.diagnostics["lamWs"]["rhat"] == [math.inf] * len(rh)  # [None] before
    assert loaded.convergence["rhat"]["lamWs"] == [math.inf] * len(rh)
