"""full_prediction takes every pair of experiments' grids the fit takes for a 'linear'
discrepancy: the reduction lets their largest |index| differ by up to 1e-12 relative
(`_check_discrepancy_scales`), which moves the basis' scale 1 / sqrt(1 + index^2) by at most
as much, and full_prediction compares those scales (session 93 review)."""

from __future__ import annotations

import numpy as np
import pytest
from _calib_cases import one_component_functional
from test_full_prediction_rest_s93 import X_OBS, _predict

import gpmsa
from gpmsa import GPMSAError
from gpmsa.fitting.emulator import Emulator
from gpmsa.model.problem import _check_discrepancy_scales


def _edge(top: float) -> float:
    """The smallest index whose distance from ``top`` the fit's check (rtol 1e-12 of the
    smaller) still lets pass."""
    low = top * (1.0 - 1e-12)
    while not np.isclose(top, low, rtol=1e-12, atol=0.0):
        low = np.nextafter(low, np.inf)
    while np.isclose(top, np.nextafter(low, -np.inf), rtol=1e-12, atol=0.0):
        low = np.nextafter(low, -np.inf)
    return float(low)


def _scaled(top: float) -> Emulator:
    """`one_component_functional` on the index grid [0, top / 3, 2 top / 3, top]."""
    emu, grid = one_component_functional()
    sim = gpmsa.SimData(x=emu.x_unit, t=emu.t_unit, y=emu.y, index=grid * top, x_names=["x"],
                        t_names=["t"])  # fmt: skip
    return Emulator.from_params(sim, dict(emu.params), n_pc=1)


@pytest.mark.parametrize("top", [1e3, 1e9, 1e12])
def test_grids_at_the_fits_edge_are_predicted_with_the_first_experiments_scale(top):
    low = _edge(top)
    grids = [np.array([0.0, top]), np.array([0.0, low])]
    _check_discrepancy_scales("linear", grids)  # the fit takes them
    obs = gpmsa.ObsData(x=X_OBS, y=[[1.5, 2.0], [1.8, 2.4]], index=[list(g) for g in grids])
    pred = _predict(obs, _scaled(top), discrepancy="linear", grid=[0.0, top])
    want = np.array([[1.0, 0.0], [1.0, top]]) / np.sqrt(1.0 + top**2)
    np.testing.assert_allclose(pred.D, want, rtol=1e-14)


def test_grids_twice_the_fits_tolerance_apart_are_refused_by_both():
    top = 1e3
    grids = [np.array([0.0, top]), np.array([0.0, top * (1.0 - 2e-12)])]
    with pytest.raises(GPMSAError, match="^discrepancy='linear' is normalised on each"):
        _check_discrepancy_scales("linear", grids)
    std = _scaled(top).standardizer
    with pytest.raises(GPMSAError, match="^the experiments' grids give the 'linear' discrep"):
        gpmsa.predictive.full._pred_discrepancy("linear", grids, std, grids[0], False)
