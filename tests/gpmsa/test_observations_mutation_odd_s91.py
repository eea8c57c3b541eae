"""Mutation testing of gpmsa/calibration/observations.py, the odd half of its sites (session
91): exact checks, on small hand-built cases, of what the existing tests left open."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from _calib_cases import one_component_functional

from gpmsa.calibration import observations as obsmod
from gpmsa.errors import ExtrapolationWarning, GPMSAError


def test_fixed_gp_refuses_a_separable_emulator_above_the_dense_limit(monkeypatch):
    from gpmsa.model import kronecker

    monkeypatch.setattr(kronecker, "MAX_DENSE_RUNS", 4)
    emu = SimpleNamespace(separable=object(), m=5)
    msg = r"^calibration \(gpmsa.calibrate, gpmsa.Calibrator\) builds the dense 5 x 5 Sigma_W"
    with pytest.raises(GPMSAError, match=msg):
        obsmod.fixed_gp(emu, {})


def test_fit_is_a_frozen_hashable_value():
    import dataclasses

    fit = obsmod.Fit(7.25, 0.5)
    assert hash(fit) == hash(obsmod.Fit(7.25, 0.5)) and fit == obsmod.Fit(7.25, 0.5)
    with pytest.raises(dataclasses.FrozenInstanceError):
        fit.outside_sds = 0.0  # type: ignore[misc]


def test_reduce_of_a_functional_output_extrapolates_x_where_allowed():
    # x beyond the design's range by more than the margin: refused, or (extrapolate=True)
    # reduced with a warning; the multi-output reduction must not check x again and refuse it
    emu, grid = one_component_functional()
    y_obs = [3.0 * (1.0 + grid)]
    with pytest.raises(GPMSAError, match="extrapolate=True"):
        obsmod.reduce(emu, [[2.0]], y_obs)
    with pytest.warns(ExtrapolationWarning):
        data = obsmod.reduce(emu, [[2.0]], y_obs, extrapolate=True)
    assert data.x.tolist() == [[2.0]] and data.z.shape == (1,)


def test_excess_solves_with_the_lower_cholesky_factor():
    # Sigma_obs = L L^T, L = [[1, 0], [1, 1]]: L^-1 r = (1, 2) for r = (1, 3), |.|^2 = 5;
    # tr(L^-1 I L^-T) = |L^-1|_F^2 = |[[1, 0], [-1, 1]]|^2 = 3; excess (5 - 3) / d = 1
    L = np.array([[1.0, 0.0], [1.0, 1.0]])
    data = SimpleNamespace(obs_chol=L, z=np.zeros(2), obs=SimpleNamespace(n_null=0))
    cov = np.eye(2)[None, None]  # (G, p_u, n, n) = (1, 1, 2, 2)
    resid = np.array([[1.0, 3.0]])
    excess = obsmod._excess(resid, np.ones((1, 2)), cov, data, np.linalg.inv(L))
    assert excess.tolist() == [1.0]


def test_theta_levels_native_refuses_levels_that_do_not_match_the_names():
    emu = SimpleNamespace(levels=((5, 6), (1, 2), (3, 4)), x_names=["c"], t_names=["a"])
    with pytest.raises(ValueError, match="zip"):
        obsmod.theta_levels_native(emu)
