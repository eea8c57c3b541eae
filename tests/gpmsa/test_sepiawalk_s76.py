"""A SEPIA user's port (ball drop, Neddermeyer): a multi-column output index, SEPIA's (p_v, l)
discrepancy layout, and the discrepancy basis on another grid (SEPIA's D_sim)."""

import numpy as np
import pytest

import gpmsa

H_SIM = np.arange(1.5, 25, 1.5)
H_OBS = np.array([5.0, 10.0, 15.0, 20.0])


def _kernels(h: np.ndarray) -> np.ndarray:
    """Normal kernels (sd 1.5) centred on the simulation heights, one column each."""
    return np.exp(-0.5 * ((h[:, None] - H_SIM[None, :]) / 1.5) ** 2)


def _ball_drop():
    rng = np.random.default_rng(0)
    r, c = rng.uniform(0.05, 0.45, 20), rng.uniform(0.05, 0.25, 20)
    y = np.sqrt(H_SIM[None, :]) * (0.45 + c[:, None] / r[:, None] * 0.1)
    sim = gpmsa.SimData(x=r[:, None], t=c[:, None], y=y, index=H_SIM)
    r_obs = np.array([0.1, 0.2, 0.4])
    y_obs = np.sqrt(H_OBS)[None, :] * (0.5 + 0.03 / r_obs[:, None]) + 0.01 * H_OBS / 20
    return sim, gpmsa.ObsData(x=r_obs[:, None], y=y_obs, index=H_OBS)


def test_sim_index_of_several_columns_is_points_its_transpose_named():
    t, phi = np.linspace(0, 1, 4), np.linspace(0, 6, 5)
    ind = np.column_stack([np.repeat(t, 5), np.tile(phi, 4)])  # SEPIA's (l, 2) y_ind_sim
    run = {"x": np.arange(5.0)[:, None], "t": np.arange(5.0)[::-1, None] ** 2,
           "y": np.arange(100.0).reshape(5, 20)}  # fmt: skip
    assert gpmsa.SimData(**run, index=ind).grid.shape == (20, 2)
    with pytest.raises(gpmsa.GPMSAError, match=r"\(20,\) or .*\(20, d\), got shape \(2, 20\)"):
        gpmsa.SimData(**run, index=ind.T)


def test_obs_index_of_several_columns_is_points():
    ind = [np.column_stack([np.full(3, 0.5), [1.0, 2.0, 3.0]])] * 2
    obs = gpmsa.ObsData(x=[[0.1], [0.2]], y=[np.ones(3), np.ones(3)], index=ind)
    assert [g.shape for g in obs.grids] == [(3, 2), (3, 2)]


def test_discrepancy_array_in_sepia_layout_says_transpose():
    sim, obs = _ball_drop()
    with pytest.raises(gpmsa.GPMSAError, match="pass its transpose"):
        gpmsa.fit(sim, obs, n_iter=20, tune=False, seed=0, n_pc=2,
                  discrepancy=_kernels(H_OBS).T)  # fmt: skip


def test_grid_discrepancy_gives_delta_on_the_simulation_grid():
    sim, obs = _ball_drop()
    d_obs = _kernels(H_OBS)
    emu = gpmsa.fit(sim, obs, n_iter=60, tune=False, seed=0, n_pc=2, discrepancy=d_obs)
    base = gpmsa.full_prediction(emu, obs, [[0.2]], discrepancy=d_obs, seed=1)
    same = gpmsa.full_prediction(emu, obs, [[0.2]], discrepancy=d_obs, seed=1,
                                 grid_discrepancy=d_obs)  # fmt: skip
    assert np.array_equal(base.delta, same.delta) and np.array_equal(base.y, same.y)
    with pytest.raises(gpmsa.GPMSAError, match="known on the observations' grid only"):
        gpmsa.full_prediction(emu, obs, [[0.2]], discrepancy=d_obs, grid=H_SIM)
    on_sim = gpmsa.full_prediction(emu, obs, [[0.2]], discrepancy=d_obs, seed=1, grid=H_SIM,
                                   grid_discrepancy=_kernels(H_SIM))  # fmt: skip
    scale = np.sqrt(np.max(np.sum(d_obs**2, axis=1)))  # the fit's normalisation
    expected = (on_sim.v @ (_kernels(H_SIM) / scale).T) * emu.standardizer.sd_on(H_SIM)
    np.testing.assert_allclose(on_sim.delta, expected, rtol=1e-12, atol=1e-15)
    assert on_sim.delta.shape[-1] == H_SIM.size
    with pytest.raises(gpmsa.GPMSAError, match=r"must be \(16, 16\).*got \(4, 16\)"):
        gpmsa.full_prediction(emu, obs, [[0.2]], discrepancy=d_obs, grid=H_SIM,
                              grid_discrepancy=_kernels(H_SIM)[:, :4].T)  # fmt: skip
    with pytest.raises(gpmsa.GPMSAError, match="both choose"):
        gpmsa.full_prediction(emu, obs, [[0.2]], discrepancy=d_obs, experiment=0,
                              grid_discrepancy=d_obs)  # fmt: skip


def test_grid_discrepancy_refused_for_a_named_basis():
    sim, obs = _ball_drop()
    emu = gpmsa.fit(sim, obs, n_iter=40, tune=False, seed=0, n_pc=2, discrepancy="linear")
    with pytest.raises(gpmsa.GPMSAError, match="goes with a discrepancy basis given as an array"):
        gpmsa.full_prediction(emu, obs, [[0.2]], grid=H_SIM, grid_discrepancy=np.ones((16, 2)))
