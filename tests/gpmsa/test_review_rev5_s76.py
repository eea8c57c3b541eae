"""Review of session 76's grid_discrepancy= (full_prediction) and the studies' at-bound record.

Before: a joint fit with per-experiment bases predicted with its kept (normalised) list and
``grid_discrepancy=`` left the new grid's basis unnormalised (delta 3.3 times the observations'
grid's on that grid); a Study pickled before ``info["at_bound"]`` existed raised KeyError from
``member_posterior``; SEPIA's one (l, 2) y_ind_obs array was refused as "index has 3 grids
for 2 experiment(s)"."""

from __future__ import annotations

import pickle
import warnings

import numpy as np
import pytest

import gpmsa
from tests.gpmsa._study_cases import emulator, observations

H_SIM = np.arange(1.5, 25, 1.5)
G0, G1 = np.array([5.0, 10.0, 15.0, 20.0]), np.array([4.5, 9.0, 13.5, 18.0, 22.5])


def _kernels(h: np.ndarray) -> np.ndarray:
    """Four kernels of height 3 (so that the fit's normalisation is not 1)."""
    return 3.0 * np.exp(-0.5 * ((h[:, None] - H_SIM[None, :16:4]) / 4.0) ** 2)


def _ragged_fit():
    rng = np.random.default_rng(0)
    r, c = rng.uniform(0.05, 0.45, 20), rng.uniform(0.05, 0.25, 20)
    y = np.sqrt(H_SIM[None, :]) * (0.45 + c[:, None] / r[:, None] * 0.1)
    sim = gpmsa.SimData(x=r[:, None], t=c[:, None], y=y, index=H_SIM)
    ys = [np.sqrt(g) * (0.5 + 0.03 / ro) + 0.01 * g / 20 for g, ro in ((G0, 0.1), (G1, 0.2))]
    obs = gpmsa.ObsData(x=[[0.1], [0.2]], y=ys, index=[G0, G1])
    D = [_kernels(G0), _kernels(G1)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, obs, n_iter=30, tune=False, seed=0, n_pc=2, discrepancy=D)
    return emu, obs, D


def test_grid_discrepancy_with_a_joint_fits_kept_list_is_refused():
    """The kept list is normalised: without the fit's recorded scale (a file written before
    settings "discrepancy_scale"; with it: test_gridscale_s77), dividing grid_discrepancy by
    the list's own (1) left delta 3.3 times too large; the list given to the fit normalises
    it exactly."""
    emu, obs, D = _ragged_fit()
    del emu.settings["discrepancy_scale"]
    kw = {"seed": 1, "n_draws": 5}
    for kept in ({}, {"discrepancy": emu.discrepancy_bases}):
        with pytest.raises(gpmsa.GPMSAError, match="pass the list given to the fit again"):
            gpmsa.full_prediction(emu, obs, [[0.2]], grid=G0, grid_discrepancy=_kernels(G0),
                                  **kept, **kw)  # fmt: skip
    base = gpmsa.full_prediction(emu, obs, [[0.2]], grid=G0, **kw)
    same = gpmsa.full_prediction(emu, obs, [[0.2]], discrepancy=D, grid=G0,
                                 grid_discrepancy=_kernels(G0), **kw)  # fmt: skip
    assert np.array_equal(base.delta, same.delta)
    on_sim = gpmsa.full_prediction(emu, obs, [[0.2]], discrepancy=D, grid=H_SIM,
                                   grid_discrepancy=_kernels(H_SIM), **kw)  # fmt: skip
    scale = np.sqrt(max(np.max(np.sum(d**2, axis=1)) for d in D))
    expected = (on_sim.v @ (_kernels(H_SIM) / scale).T) * emu.standardizer.sd_on(H_SIM)
    np.testing.assert_allclose(on_sim.delta, expected, rtol=1e-12, atol=1e-15)


def test_a_study_pickled_before_the_at_bound_record_is_judged_on_unpickling():
    rng = np.random.default_rng(4)
    data = [observations(th, 4, 0.02, rng) for th in (1.03, 1.03)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        study = gpmsa.calibrate_study([emulator(None)] * 2, [d[0] for d in data],
                                      [d[1] for d in data], labels=["a", "b"], shared=["t"],
                                      n_samples=300, n_burn=100, seed=5, tune_rounds=3)  # fmt: skip
    flagged = study.posterior.info["at_bound"]
    assert flagged == {"t": "upper"}
    del study.posterior.info["at_bound"]  # as a Study pickled before it was recorded
    back = pickle.loads(pickle.dumps(study))
    assert back.posterior.info["at_bound"] == flagged
    assert back.member_posterior("b").info["at_bound"] == {"t": "upper"}


def test_one_multi_column_obs_index_array_is_every_experiments_points():
    """SEPIA's y_ind_obs, one (l_obs, 2) array of (time, angle) pairs for every experiment."""
    ind = np.column_stack([np.full(3, 0.5), [1.0, 2.0, 3.0]])
    for n in (2, 3):  # n = 3: read before as 3 grids of 2 points
        obs = gpmsa.ObsData(x=np.arange(n)[:, None] / 4, y=np.ones((n, 3)), index=ind)
        assert all(np.array_equal(g, ind) for g in obs.grids) and len(obs.grids) == n
    grids = gpmsa.ObsData(x=[[0.1], [0.2], [0.3]], y=np.ones((3, 2)),
                          index=np.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]])).grids  # fmt: skip
    assert [list(g) for g in grids] == [[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]]  # (n, l): per row
