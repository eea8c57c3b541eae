"""Session 67's review: what it found in the session's own changes.

- ``gpmsa info`` put each element's ESS and R-hat in its place only where it was held: a
  value stored as null (non-finite) among the others was left out, and the next element's
  took its place (the shift session 67 fixed for held elements).
- ``Calibrator(mcmc_options={"backend": array})`` raised numpy's "truth value of an array is
  ambiguous" where any other value that is no backend is a GPMSAError naming it.
"""

import copy
import warnings

import numpy as np
import pytest
from _study_cases import emulator

import gpmsa
from gpmsa import GPMSAError
from gpmsa.cli import info
from gpmsa.io.container import read_raw


def test_gpmsa_info_keeps_each_elements_ess_in_its_place_after_a_null(tmp_path):
    rng = np.random.default_rng(0)
    x, t = rng.uniform(0, 1, (12, 1)), rng.uniform(0, 1, (12, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # so short a fit is not converged
        emu = gpmsa.fit(gpmsa.SimData(x, t, np.sin(3 * x) + t), n_iter=12, n_chains=2,
                        n_jobs=1, tune=False, seed=0)  # fmt: skip
    manifest, arrays = read_raw(emu.save(tmp_path / "e.gpmsa"))
    doctored = copy.deepcopy(manifest)
    diag = doctored["diagnostics"]["betaU"]
    diag["ess"] = [None, 123.0]  # element 0's ESS not finite (a stuck chain), element 1's 123
    diag["rhat"] = [None, None]  # none to give: left out, as before
    lines = info._lines("e.gpmsa", doctored, arrays, emu)
    line = next(ln for ln in lines if ln.startswith("posterior betaU"))
    assert "ESS [nan, 123] R-hat []" in line


@pytest.mark.parametrize("given", [np.array(["torch", "numpy"]), np.array("torch")])
def test_a_calibrators_mcmc_options_backend_that_is_an_array_is_refused_naming_it(given):
    with pytest.raises(GPMSAError, match=r"mcmc_options\['backend'\]=array"):
        gpmsa.Calibrator(emulator(None), mcmc_options={"backend": given}, backend="torch")
