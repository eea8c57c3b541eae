"""Exact cases from mutation testing of ``gpmsa/calibration/calibrator.py`` (session 93, a sample:
every 3rd site): the memory charged for a grid posterior's draws and for its grid, the number of
points per call of a callable prior while its zero region's edge is bisected, and empty step widths
with pyro."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from _calib_cases import one_t_emulator, recorded_edge_prior, road_emulator

import gpmsa
from gpmsa import Calibrator, limits
from gpmsa.calibration import calibrator as calibrator_module
from gpmsa.errors import GPMSAError, ResourceLimitError
from gpmsa.fitting.emulator import Emulator


@pytest.mark.parametrize("n_draws", [10**6, 2 * 10**6 + 1])
def test_the_draws_are_charged_three_arrays_of_eight_bytes_per_parameter(monkeypatch, n_draws):
    """8 bytes x 3 arrays x n_draws x (q + 1) parameters (theta and lamOs): exactly at the limit
    it is built, a byte under it refused by name (the grid's own charge is far smaller)."""
    emu, _, _ = one_t_emulator()  # q = 1
    need = 8 * 3 * n_draws * 2
    monkeypatch.setattr(limits, "MAX_MEMORY_BYTES", need)
    assert Calibrator(emu, n_draws=n_draws).n_draws == n_draws
    monkeypatch.setattr(limits, "MAX_MEMORY_BYTES", need - 1)
    with pytest.raises(ResourceLimitError, match=rf"n_draws={n_draws}\): the posterior's draws"):
        Calibrator(emu, n_draws=n_draws)


def test_the_grid_is_charged_its_correlations_and_factor_per_parameter_set(monkeypatch):
    """Per set 8 bytes x p_u x (2 G m + 2 m^2), plus 8 x 8 x G: with m = 200 runs, G = 129 nodes
    and one component 1,061,056 bytes; a byte under it the grid is refused by name, at it the
    grid check passes and the emulator's GP (a larger charge, checked next) is what refuses."""
    rng = np.random.default_rng(0)
    x, t = rng.random(200), rng.random(200)
    sim = gpmsa.SimData(x[:, None], t[:, None], (x + t)[:, None], x_names=["x"], t_names=["t"])
    emu = Emulator.from_params(sim, {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3],
                                     "lamWOs": [1e3]})  # fmt: skip
    need = 8 * (2 * 129 * 200 + 2 * 200**2) + 8 * 8 * 129
    assert need == 1_061_056
    monkeypatch.setattr(limits, "MAX_MEMORY_BYTES", need - 1)
    with pytest.raises(
        ResourceLimitError, match=r"^Calibrator\(n_grid=129\): 129 grid nodes x 200"
    ):
        Calibrator(emu, n_draws=1)
    monkeypatch.setattr(limits, "MAX_MEMORY_BYTES", need)
    with pytest.raises(ResourceLimitError, match=r"^the emulator's GP \(200 runs"):
        Calibrator(emu, n_draws=1)


def test_a_callable_priors_zero_edge_is_bisected_four_steps_a_call():
    """One parameter, no constraint: the edge of the prior's zero region is located by calls of
    2**PRIOR_BISECT_LEVELS - 1 = 15 points each (four bisection steps a call), 12 calls (48
    steps) from the node spacing 1/128 down to adjacent floats near 0.61; before them the grid's
    129 nodes, after them the edge's one inserted point."""
    emu, x, y = one_t_emulator()
    sizes = []
    prior = recorded_edge_prior(0.6137, sizes)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = Calibrator(emu, seed=1).update(x, y, prior=prior)
    assert calibrator_module.PRIOR_BISECT_LEVELS == 4
    assert sizes == [(129,)] + [(15,)] * 12 + [(1,)]
    assert post.grids["t"].nodes[0] == pytest.approx(0.6137, abs=1e-15)


def test_empty_step_widths_are_not_given_to_pyro():
    """``step_widths=[]`` is no step widths (calibrate and pyro's ``sample`` read it so): a pyro
    Calibrator takes it, as it refuses non-empty ones."""
    pytest.importorskip("pyro")
    cal = Calibrator(road_emulator(), backend="pyro", mcmc_options={"step_widths": []})
    assert cal.method == "mcmc"
    with pytest.raises(GPMSAError, match=r"mcmc_options \['step_widths'\]: backend 'pyro'"):
        Calibrator(road_emulator(), backend="pyro", mcmc_options={"step_widths": [0.1]})


def test_the_theta_grid_is_read_only_when_built():
    """``theta_grid`` is handed out (`log_likelihood_grid`): read-only from the constructor on,
    not only after unpickling."""
    cal = Calibrator(one_t_emulator()[0])
    assert cal.theta_grid.flags.writeable is False
    with pytest.raises(ValueError, match="read-only"):
        cal.theta_grid[0] = 1.0
