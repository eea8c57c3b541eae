"""emulator_prediction, full_prediction and cross_validate with categorical inputs and a mean
basis (docs/categorical-and-constraints.md): against Emulator.predict and Emulator.loo, and
against brute-force Gaussian conditioning written out densely here."""

import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa.model.correlation import correlation
from gpmsa.model.problem import reduce_obs
from gpmsa.predictive.full import _posterior_sets

SHIFT = np.array([0.0, 1.0, -0.7])


def _fit(sim, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # few sweeps: convergence warnings
        return gpmsa.fit(sim, n_iter=40, seed=1, tune=False, **kw)


@cache
def case(name: str) -> gpmsa.Emulator:
    """A categorical x, a categorical t, a constant and a linear (with a categorical x) mean
    basis; 24 runs, short chains (the draws only need to differ)."""
    rng = np.random.default_rng(0)
    m = 24
    s, level, t = rng.random(m), np.arange(m) % 3, rng.random(m)
    y = np.sin(3 * s) + t + SHIFT[level]
    if name == "cat_x":
        return _fit(gpmsa.SimData(np.column_stack([s, level]), t[:, None], y, x_categorical=[1]))
    if name == "cat_t":
        tt = np.column_stack([t, level % 2])
        return _fit(gpmsa.SimData(s[:, None], tt, y + tt[:, 1], t_categorical=[1]))
    if name == "constant":
        return _fit(gpmsa.SimData(s[:, None], t[:, None], y + 2.0), mean_basis="constant")
    x = np.column_stack([s, level])
    return _fit(gpmsa.SimData(x, t[:, None], y + 2 * s, x_categorical=[1]), mean_basis="linear")


def new_points(emu):
    x = np.column_stack([[0.2, 0.5, 0.9, 0.5], [0, 2, 1, 2]])[:, : emu.p]
    t = np.column_stack([[0.3, 0.6, 0.2, 0.65], [1, 0, 1, 0]])[:, : emu.q]
    return x, t


def brute_w(emu, prm, z):
    """Dense conditional of the weight GP (p_u = 1) at unit points z given the runs' w, with
    the mean basis's coefficients (flat prior) integrated out: the universal-kriging formulas."""
    cat, lam = emu.categorical_mask, prm["lamUz"][0]
    S = correlation(emu.zt, None, prm["betaU"][:, 0], cat) / lam
    S += np.eye(emu.m) * (1 / (emu.lam_sim[0] * prm["lamWOs"][0]) + 1 / prm["lamWs"][0])
    r = correlation(z, emu.zt, prm["betaU"][:, 0], cat) / lam
    Si, w = np.linalg.inv(S), emu.w[:, 0]
    mean, cov = r @ Si @ w, correlation(z, None, prm["betaU"][:, 0], cat) / lam - r @ Si @ r.T
    if emu.mean_basis is not None:
        H, h = emu.mean_basis.matrix(emu.zt), emu.mean_basis.matrix(z)
        Q = H.T @ Si @ H
        c = np.linalg.solve(Q, H.T @ Si @ w)
        g = h.T - H.T @ Si @ r.T
        mean, cov = h @ c + r @ Si @ (w - H @ c), cov + g.T @ np.linalg.solve(Q, g)
    return mean, cov


@pytest.mark.parametrize("name", ["cat_x", "cat_t", "constant", "linear"])
def test_emulator_prediction_agrees_with_predict(name):
    emu = case(name)
    x, t = new_points(emu)
    for draws in (False, True):
        mean, var = emu.predict(x, t, draws=draws, n_draws=6)
        for joint in (False, True):
            pred = gpmsa.emulator_prediction(emu, x, t, draws=draws, n_draws=6, joint=joint, seed=0)
            assert np.max(np.abs(pred.mean() - mean)) < 1e-10 * np.max(np.abs(mean))
            assert np.max(np.abs(pred.var() / var - 1)) < 1e-10


def test_emulator_prediction_joint_draws_have_the_analytic_moments():
    emu = case("linear")
    x, t = new_points(emu)
    z = np.hstack([emu.standardizer.x_to_unit(x), emu.standardizer.t_to_unit(t)])
    mean, cov = brute_w(emu, emu.params, z)
    cov += np.eye(len(z)) / emu.params["lamWs"][0]  # resid=True: a new run's nugget
    n = 20_000
    pred = gpmsa.emulator_prediction(emu, x, t, draws=False, n_rlz=n, joint=True, seed=3)
    assert np.allclose(pred.mu_w[0, :, 0], mean, rtol=1e-9, atol=1e-12)
    w = pred.w[:, :, 0]
    sd = np.sqrt(np.diag(cov))
    assert np.max(np.abs(w.mean(axis=0) - mean) / (sd / np.sqrt(n))) < 4.5
    se = np.sqrt((np.outer(sd**2, sd**2) + cov**2) / n)  # of a Gaussian's sample covariance
    assert np.max(np.abs(np.cov(w.T) - cov) / se) < 4.5
    assert cov[1, 3] > 0.5 * np.sqrt(cov[1, 1] * cov[3, 3])  # close points: correlated


def test_cross_validate_matches_brute_force_leave_one_out():
    rng = np.random.default_rng(2)
    m = 18
    s, level, t = rng.random(m), np.arange(m) % 3, rng.random(m)
    sim = gpmsa.SimData(np.column_stack([s, level]), t[:, None], np.sin(3 * s) + t + SHIFT[level],
                        x_categorical=[1])  # fmt: skip
    emu = _fit(sim, mean_basis="constant")
    cv = gpmsa.cross_validate(emu, draws=False)
    prm = emu.params
    for i in range(m):  # the runs without run i, the same parameters
        keep = np.arange(m) != i
        mean, var = _held_out(emu, prm, keep, i)
        assert cv.mean_w[i, 0] == pytest.approx(mean, abs=1e-10)
        assert cv.var_w[i, 0] == pytest.approx(var, rel=1e-8)  # S_ii - ...: cancellation
    assert np.allclose(cv.mean, emu.loo().mean, rtol=0, atol=1e-12)
    labels = np.arange(m) // 2  # folds of two runs: their joint conditional's diagonal
    cv2 = gpmsa.cross_validate(emu, folds=labels, draws=False)
    for f in (0, 5):
        F = np.flatnonzero(labels == f)
        mean, var = _held_out(emu, prm, labels != f, F)
        assert np.allclose(cv2.mean_w[F, 0], mean, atol=1e-10)
        assert np.allclose(cv2.var_w[F, 0], var, rtol=1e-8)
    d = gpmsa.cross_validate(emu, n_draws=3)  # the draws' mixture
    assert np.all(np.isfinite(d.pit)) and d.mean.shape == (m, 1)


def _held_out(emu, prm, keep, out):
    """Mean and variance of run(s) ``out``'s weight given the runs ``keep`` (a new noisy run:
    the nugget included), the constant mean's coefficient refitted on ``keep``."""
    cat, lam = emu.categorical_mask, prm["lamUz"][0]
    S = correlation(emu.zt, None, prm["betaU"][:, 0], cat) / lam
    S += np.eye(emu.m) * (1 / (emu.lam_sim[0] * prm["lamWOs"][0]) + 1 / prm["lamWs"][0])
    Skk, Sok = S[np.ix_(keep, keep)], S[np.ix_(np.atleast_1d(out), keep)]
    Si, w = np.linalg.inv(Skk), emu.w[keep, 0]
    H = emu.mean_basis.matrix(emu.zt)
    Hk, Ho = H[keep], H[np.atleast_1d(out)]
    Q = Hk.T @ Si @ Hk
    c = np.linalg.solve(Q, Hk.T @ Si @ w)
    g = Ho.T - Hk.T @ Si @ Sok.T
    mean = Ho @ c + Sok @ Si @ (w - Hk @ c)
    cov = S[np.ix_(np.atleast_1d(out), np.atleast_1d(out))] - Sok @ Si @ Sok.T
    cov = cov + g.T @ np.linalg.solve(Q, g)
    return np.squeeze(mean), np.squeeze(np.diag(cov))


def test_cross_validate_refuses_a_fold_that_leaves_the_mean_basis_unidentified():
    rng = np.random.default_rng(2)
    m = 18
    s, level = rng.random(m), np.arange(m) % 3
    sim = gpmsa.SimData(np.column_stack([s, level]), rng.random((m, 1)), s + SHIFT[level],
                        x_categorical=[1])  # fmt: skip

    def per_level(z):  # one column per level (unit codes 0, 0.5, 1)
        return np.column_stack([np.isclose(z[:, 1], v) for v in (0.0, 0.5, 1.0)]).astype(float)

    emu = _fit(sim, mean_basis=per_level)
    assert gpmsa.cross_validate(emu, draws=False).mean.shape == (m, 1)
    with pytest.raises(gpmsa.GPMSAError, match="without fold 0 .* rank 2, so its coefficients"):
        gpmsa.cross_validate(emu, folds=level, draws=False)


@pytest.mark.parametrize("mean_basis", [None, "linear"])
def test_full_prediction_with_categorical_x_matches_dense_conditioning(mean_basis):
    rng = np.random.default_rng(0)
    m = 14
    x = np.column_stack([rng.random(m), np.arange(m) % 2])
    t = rng.random((m, 1))
    sim = gpmsa.SimData(x, t, np.sin(3 * x[:, 0]) + t[:, 0] + 0.8 * x[:, 1], x_categorical=[1])
    xo = np.array([[0.2, 0], [0.5, 1], [0.8, 0]])
    obs = gpmsa.ObsData(xo, np.sin(3 * xo[:, 0]) + 0.6 + 0.8 * xo[:, 1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, obs, n_iter=20, seed=1, tune=False, discrepancy="constant",
                        mean_basis=mean_basis)  # fmt: skip
    xn = np.array([[0.3, 1], [0.6, 0], [0.62, 1]])
    fp = gpmsa.full_prediction(emu, obs, xn, n_draws=2, seed=0)
    _, sets = _posterior_sets(emu, None, 2)
    ob, _ = reduce_obs(obs, emu.standardizer, emu.K, "constant", emu.x_names, emu.levels)
    n, N, cat = len(xo), len(xn), emu.categorical_mask
    for s, prm in enumerate(sets):
        # Observed Y = [w (m); z (n)], z = u_obs + v_obs + e; target [v_new (N); u_new (N)].
        X = np.vstack([ob.x, emu.standardizer.x_to_unit(xn)])
        XT = np.hstack([X, np.tile(prm["theta"], (n + N, 1))])
        Ru = correlation(np.vstack([emu.zt, XT]), None, prm["betaU"][:, 0], cat) / prm["lamUz"][0]
        Rv = correlation(X, None, prm["betaV"][:, 0], cat[: emu.p]) / prm["lamVz"][0]
        nug = 1 / prm["lamWs"][0]
        d, o, a = slice(0, m), slice(m, m + n), slice(m + n, m + n + N)
        Syy = np.block([
            [Ru[d, d] + np.eye(m) * (1 / (emu.lam_sim[0] * prm["lamWOs"][0]) + nug), Ru[d, o]],
            [Ru[o, d], Ru[o, o] + nug * np.eye(n) + Rv[:n, :n] + ob.sig_obs / prm["lamOs"]],
        ])  # fmt: skip
        Sty = np.block([[np.zeros((N, m)), Rv[n:, :n]], [Ru[a, d], Ru[a, o]]])
        Stt = np.block(
            [[Rv[n:, n:], np.zeros((N, N))], [np.zeros((N, N)), Ru[a, a] + nug * np.eye(N)]]
        )
        Y, Si = np.concatenate([emu.w[:, 0], ob.z]), np.linalg.inv(Syy)
        if mean_basis is None:
            mean, cov = Sty @ Si @ Y, Stt - Sty @ Si @ Sty.T
        else:  # the coefficients (flat prior) integrated out over w and the observations
            h = emu.mean_basis.matrix
            F = np.vstack([h(emu.zt), h(XT[:n])])
            FT = np.vstack([np.zeros((N, F.shape[1])), h(XT[n:])])
            Q = F.T @ Si @ F
            c = np.linalg.solve(Q, F.T @ Si @ Y)
            g = FT.T - F.T @ Si @ Sty.T
            mean = FT @ c + Sty @ Si @ (Y - F @ c)
            cov = Stt - Sty @ Si @ Sty.T + g.T @ np.linalg.solve(Q, g)
        assert np.allclose(fp.mu[s], mean.reshape(2, N).T, rtol=0, atol=1e-10)
        for i in range(N):
            block = cov[np.ix_([i, N + i], [i, N + i])]
            assert np.allclose(fp.cov[s][i], block, rtol=1e-9, atol=1e-12)


def test_unseen_levels_are_refused_by_name():
    emu = case("cat_x")
    with pytest.raises(gpmsa.GPMSAError, match="x: categorical input x1 has level 3, never seen"):
        gpmsa.emulator_prediction(emu, [[0.5, 3]], [[0.5]])
    with pytest.raises(gpmsa.GPMSAError, match="x1 has level 1.5, never seen"):
        gpmsa.emulator_prediction(emu, [[0.5, 1.5]], [[0.5]])
    with pytest.raises(gpmsa.GPMSAError, match="t: categorical input t1 has level 2, never"):
        gpmsa.emulator_prediction(case("cat_t"), [[0.5]], [[0.5, 2]])
    obs = gpmsa.ObsData([[0.3, 0], [0.6, 1]], [0.5, 1.8])
    post = gpmsa.Posterior({"t0": np.full(4, 0.5), "lamOs": np.full(4, 100.0)})
    with pytest.raises(gpmsa.GPMSAError, match="x: categorical input x1 has level 5"):
        gpmsa.full_prediction(emu, obs, [[0.5, 5]], posterior=post, discrepancy=None)
    bad = gpmsa.ObsData([[0.3, 0], [0.6, 4]], [0.5, 1.8])
    with pytest.raises(gpmsa.GPMSAError, match="obs: categorical input x1 has level 4"):
        gpmsa.full_prediction(emu, bad, [[0.5, 1]], posterior=post, discrepancy=None)
    off = gpmsa.Posterior({"t0": np.full(4, 0.5), "t1": np.full(4, 0.5),
                           "lamOs": np.full(4, 100.0)})  # fmt: skip
    with pytest.raises(gpmsa.GPMSAError, match="posterior theta: categorical input t1 has level"):
        gpmsa.full_prediction(case("cat_t"), gpmsa.ObsData([[0.3]], [0.5]), [[0.5]],
                              posterior=off, discrepancy=None)  # fmt: skip
