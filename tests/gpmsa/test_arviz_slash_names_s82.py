"""A parameter name holding "/" and ``to_arviz`` with ArviZ 1.x (session 82 review).

Before: with ArviZ 1.x (checked with 1.3.0 on Python 3.13) every ``to_arviz`` of such a
posterior (a Posterior's, an Emulator's, a study's) raised xarray's ValueError "Variables stored
in DataTree objects cannot have names containing '/' characters", naming neither the parameter's
remedy nor gpmsa; docs/calibration.md's ``idata.rename(...)`` cannot run on what never came back.
ArviZ 0.x's InferenceData takes the name (its ``to_netcdf`` refuses it)."""

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.mcmc import diagnostics

pytest.importorskip("arviz")

CHAINS = {"E/rho": np.arange(20.0).reshape(2, 10), "GD": np.ones((2, 10))}


def _posterior():
    return gpmsa.Posterior({k: v.reshape(-1) for k, v in CHAINS.items()}, chains=CHAINS)


def test_a_slash_in_a_name_is_refused_naming_it_where_arviz_builds_a_datatree(monkeypatch):
    monkeypatch.setattr(diagnostics, "arviz_major", lambda: 1)
    with pytest.raises(GPMSAError, match=r"parameter 'E/rho' holds '/', .*DataTree .*rename"):
        _posterior().to_arviz()


def test_arviz_0x_keeps_taking_a_slash_in_a_name():
    if diagnostics.arviz_major() >= 1:
        pytest.skip("ArviZ 0.x's InferenceData only")
    idata = _posterior().to_arviz()
    np.testing.assert_array_equal(idata.posterior["E/rho"].values, CHAINS["E/rho"])
