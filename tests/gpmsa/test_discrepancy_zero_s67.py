"""One experiment without discrepancy in a list of per-experiment bases: a zero block, as a
zero ``obsData(k).Dobs`` in GPM/SA (session 67).

Before: ``discrepancy=[D_0, zeros]`` was refused ("discrepancy[1] (experiment 1's basis) is all
zeros"), and a file holding such a list could not be written or read. Now the experiment's
weights' reduced data are unobserved directions (``ObsProblem.n_null``), its delta is 0, and the
file keeps the zero block; bases all zero, every experiment's, are still refused."""

import dataclasses
import functools
import warnings

import numpy as np
import pytest
from scipy.linalg import solve_triangular

import gpmsa
from gpmsa import EmulatorFileError
from gpmsa.model.correlation import correlation
from gpmsa.model.likelihood import log_likelihood
from gpmsa.model.problem import reduce_obs
from tests.gpmsa.test_discrepancy_list_s66 import GRIDS, _case, _kernels
from tests.gpmsa.test_file_hostile import read_members, write_members


def _zero_second():
    per = _kernels(GRIDS)
    return [per[0], np.zeros_like(per[1])]


def _native_log_likelihood(problem, prm):
    """The model in the outputs' own space, no reduction: y_e = K_e u_e + D_e v_e + e_e,
    e_e ~ N(0, I / lamOs), u | the runs the emulator's GP conditional, v GP(betaV, lamVz)
    (one precision group); plus the runs' part (the likelihood without observations)."""
    ob = problem.obs
    runs = log_likelihood(dataclasses.replace(problem, obs=None), prm)
    n, p_u, p_v = ob.n, problem.p_u, ob.p_v
    xt = np.hstack([ob.x, np.tile(prm["theta"], (n, 1))])
    mean, cov_u = [], np.zeros((p_u * n, p_u * n))
    for j in range(p_u):
        beta, lam = prm["betaU"][:, j], prm["lamUz"][j]
        S = correlation(problem.zt, None, beta) / lam
        S[np.diag_indices(problem.m)] += 1 / (problem.lam_sim[j] * prm["lamWOs"][0])
        S[np.diag_indices(problem.m)] += 1 / prm["lamWs"][j]
        L = np.linalg.cholesky(S)
        B = solve_triangular(L, correlation(xt, problem.zt, beta).T / lam, lower=True)
        mean.append(B.T @ solve_triangular(L, problem.w[:, j], lower=True))
        block = correlation(xt, None, beta) / lam + np.eye(n) / prm["lamWs"][j] - B.T @ B
        cov_u[j * n : (j + 1) * n, j * n : (j + 1) * n] = block
    ends = np.cumsum([0] + [K.shape[0] for K in ob.K])
    Kb, Db = np.zeros((ends[-1], p_u * n)), np.zeros((ends[-1], p_v * n))
    for e in range(n):
        Kb[ends[e] : ends[e + 1], e::n] = ob.K[e]
        Db[ends[e] : ends[e + 1], e::n] = ob.D[e]
    cov_v = np.kron(np.eye(p_v), correlation(ob.x, None, prm["betaV"][:, 0]) / prm["lamVz"][0])
    C = Kb @ cov_u @ Kb.T + Db @ cov_v @ Db.T + np.eye(ends[-1]) / prm["lamOs"][0]
    L = np.linalg.cholesky(C)
    r = solve_triangular(L, np.concatenate(ob.y_std) - Kb @ np.concatenate(mean), lower=True)
    return runs - np.sum(np.log(np.diag(L))) - 0.5 * r @ r


def _offsets(discrepancy, n_points=8):
    """reduced log-likelihood + its lamOs prior correction - the native one, at random
    parameters (their spread: the reduction's error; the native's D_1 is the zero one)."""
    data, obs = _case()
    prep = gpmsa.prepare(data, obs, discrepancy=discrepancy)
    prob = prep.problem
    da, db = reduce_obs(obs, prep.standardizer, prep.K, discrepancy, ("x",))[1]
    rng = np.random.default_rng(1)
    out = []
    for _ in range(n_points):
        prm = {k: np.array(v, dtype=float) for k, v in prob.init.items()}
        prm["theta"] = rng.uniform(0.1, 0.9, prm["theta"].shape)
        prm["betaU"] = prm["betaU"] * rng.uniform(0.5, 2.0)
        prm["betaV"] = prm["betaV"] * rng.uniform(0.3, 3.0)
        prm["lamVz"] = prm["lamVz"] * rng.uniform(0.1, 10.0)
        prm["lamOs"] = np.array([rng.uniform(0.5, 3.0)])
        lam = prm["lamOs"][0]
        reduced = log_likelihood(prob, prm) + da * np.log(lam) - db * lam
        out.append(reduced - _native_log_likelihood(prob, prm))
    return np.array(out)


def test_an_experiment_with_a_zero_basis_is_the_model_without_its_discrepancy():
    """The reduced likelihood with D_1 = 0 equals, up to a constant, the native-space Gaussian
    in which experiment 1 has no discrepancy term (y_1 = K_1 u_1 + e_1), over theta, the
    emulator's, the discrepancy's and lamOs's values; within the reduction's 1e-6 ridge
    (GPM/SA's, the same for the nonzero list: the reference's check)."""
    for discrepancy in (_kernels(GRIDS), _zero_second()):
        off = _offsets(discrepancy)
        assert np.ptp(off) < 2e-5, off
    per = _kernels(GRIDS)
    data, obs = _case()
    prob = gpmsa.prepare(data, obs, discrepancy=[per[0], 0 * per[1]]).problem
    assert prob.obs.n_null == gpmsa.prepare(data, obs, discrepancy=per).problem.obs.n_null + 1
    assert np.all(prob.obs.v[1] == 0.0)
    with pytest.raises(gpmsa.GPMSAError, match=r"all zeros, every experiment's.*=None"):
        gpmsa.prepare(data, obs, discrepancy=[0 * per[0], 0 * per[1]])


@functools.cache
def _fit():
    data, obs = _case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains
        return gpmsa.fit(data, obs, n_iter=30, tune=False, seed=3, discrepancy=_zero_second())


def test_a_zero_block_round_trips_the_file_and_its_delta_is_zero(tmp_path):
    emu = _fit()
    _, obs = _case()
    back = gpmsa.load(emu.save(tmp_path / "z.gpmsa"))  # before: refused to write
    assert back.model_sha256 == emu.model_sha256
    for a, b in zip(emu.discrepancy_bases, back.discrepancy_bases, strict=True):
        np.testing.assert_array_equal(a, b)
    assert not np.any(back.discrepancy_bases[1]) and np.any(back.discrepancy_bases[0])
    on1 = gpmsa.full_prediction(back, obs, [[0.5], [0.7]], grid=GRIDS[1], n_draws=4, seed=0)
    on0 = gpmsa.full_prediction(back, obs, [[0.5], [0.7]], grid=GRIDS[0], n_draws=4, seed=0)
    assert np.all(on1.delta == 0.0) and np.all(on1.D == 0.0)
    assert np.max(np.abs(on0.delta)) > 1e-3
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = gpmsa.calibrate(emu, obs, n_samples=20, n_burn=5, tune=False, seed=0,
                               discrepancy=_zero_second())  # fmt: skip
    assert post.info["discrepancy_sha256"] == emu.settings["discrepancy_sha256"]
    pred = gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, grid=GRIDS[1], n_draws=4,
                                 discrepancy=_zero_second(), seed=0)  # fmt: skip
    assert np.all(pred.delta == 0.0)


def _zero_first(a):
    a["discrepancy_D"] = a["discrepancy_D"].copy()
    a["discrepancy_D"][:5] = 0.0  # experiment 0's 5 rows: now every experiment's is zero


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (_zero_first, r"arrays/discrepancy_D: is not normalised: its largest diag\(D D\^T\) is 0"),
        (lambda a: a.__setitem__("discrepancy_D", a["discrepancy_D"][::-1].copy()), "digest"),
    ],
)
def test_a_damaged_zero_block_file_is_still_refused(tmp_path, edit, field):
    manifest, arrays = read_members(_fit().save(tmp_path / "z.gpmsa"))
    edit(arrays)
    with pytest.raises(EmulatorFileError, match=field):
        gpmsa.load(write_members(tmp_path / "edit.gpmsa", manifest, arrays))


def test_experiments_sharing_a_grid_predict_with_the_basis_experiment_names():
    """[D_0, zeros] with both experiments on one grid (session 67's review): full_prediction
    refused every grid ("share this grid but their discrepancy bases differ"), so such a fit
    had no prediction; ``experiment=j`` takes experiment j's basis (SEPIA's ``obs_ref``)."""
    data, _ = _case()
    grid = GRIDS[0]
    per = _kernels([grid, grid])
    obs = gpmsa.ObsData([[0.3], [0.7]], [np.interp(grid, GRIDS[0], 0.3 + grid)] * 2, index=grid)
    bases = [per[0], np.zeros_like(per[1])]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains
        emu = gpmsa.fit(data, obs, n_iter=30, tune=False, seed=3, discrepancy=bases)
    with pytest.raises(gpmsa.GPMSAError, match=r"share this grid.*experiment=j"):
        gpmsa.full_prediction(emu, obs, [[0.5]], n_draws=2, seed=0)
    on = [gpmsa.full_prediction(emu, obs, [[0.5]], n_draws=4, seed=0, experiment=j) for j in (0, 1)]
    assert np.max(np.abs(on[0].delta)) > 1e-3 and np.all(on[1].delta == 0.0)
    np.testing.assert_array_equal(on[0].mu[..., 3:], on[1].mu[..., 3:])  # the same conditional
    for bad in (2, True, 0.0):
        with pytest.raises(
            gpmsa.GPMSAError, match=rf"experiment must be an integer in \[0, 1\], got {bad}"
        ):
            gpmsa.full_prediction(emu, obs, [[0.5]], n_draws=2, experiment=bad)
    with pytest.raises(gpmsa.GPMSAError, match=r"experiment=0 predicts on its grid"):
        gpmsa.full_prediction(emu, obs, [[0.5]], n_draws=2, experiment=0, grid=grid[:3])
    one = _fit()  # its own bases on own grids: experiment=1 is grid=GRIDS[1]
    a = gpmsa.full_prediction(one, _case()[1], [[0.5]], n_draws=2, seed=0, experiment=1)
    b = gpmsa.full_prediction(one, _case()[1], [[0.5]], n_draws=2, seed=0, grid=GRIDS[1])
    np.testing.assert_array_equal(a.y, b.y)
