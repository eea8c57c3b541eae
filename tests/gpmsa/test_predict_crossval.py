"""Cross-validation over posterior draws: leave-one-out and k-fold."""

import numpy as np
import pytest
from _calib_cases import two_param_emulator
from _predict_cases import vector_fit
from scipy.special import ndtr

import gpmsa
from gpmsa import GPMSAError
from gpmsa.model.correlation import correlation
from gpmsa.predictive import cross_validate

PARAMS = ("betaU", "lamUz", "lamWs", "lamWOs")


def _held_out_by_solve(emu, prm, F):
    """Weights of runs F given the others, by a dense solve on the remaining runs only."""
    keep = np.setdiff1d(np.arange(emu.m), F)
    mean = np.empty((F.size, emu.p_u))
    var = np.empty((F.size, emu.p_u))
    for j in range(emu.p_u):
        S = correlation(emu.zt, None, prm["betaU"][:, j]) / prm["lamUz"][j]
        S[np.diag_indices(emu.m)] += 1 / (emu.lam_sim[j] * prm["lamWOs"][0]) + 1 / prm["lamWs"][j]
        A = S[np.ix_(keep, keep)]
        c = S[np.ix_(F, keep)]
        mean[:, j] = c @ np.linalg.solve(A, emu.w[keep, j])
        var[:, j] = np.diag(S[np.ix_(F, F)] - c @ np.linalg.solve(A, c.T))
    return mean, var


def _held_out_outputs_by_solve(emu, prm, F):
    """Standardised outputs of runs F given the other runs' outputs, from the dense covariance
    of all m x l_sim outputs under the model: y_i = sum_j k_j w_ij + e_i, w_j a GP with the
    nugget 1/lamWs_j, e_i ~ N(0, I / lamWOs). Mean and variance (|F|, l_sim)."""
    L = emu.l_sim
    cov = np.eye(emu.m * L) / prm["lamWOs"][0]
    for j in range(emu.p_u):
        R = correlation(emu.zt, None, prm["betaU"][:, j]) / prm["lamUz"][j]
        R[np.diag_indices(emu.m)] += 1 / prm["lamWs"][j]
        cov += np.kron(R, np.outer(emu.K[:, j], emu.K[:, j]))
    y = emu.standardizer.y_to_std(emu.y).reshape(-1)
    held = (F[:, None] * L + np.arange(L)).reshape(-1)
    kept = np.setdiff1d(np.arange(y.size), held)
    c = cov[np.ix_(held, kept)]
    mean = c @ np.linalg.solve(cov[np.ix_(kept, kept)], y[kept])
    var = np.diag(cov[np.ix_(held, held)] - c @ np.linalg.solve(cov[np.ix_(kept, kept)], c.T))
    return mean.reshape(F.size, L), var.reshape(F.size, L)


def test_point_estimate_loo_equals_emulator_loo():
    for emu in (two_param_emulator(), vector_fit()):
        cv = cross_validate(emu, draws=False)
        loo = emu.loo()
        np.testing.assert_allclose(cv.mean, loo.mean, rtol=1e-10)
        np.testing.assert_allclose(cv.var, loo.var, rtol=1e-10)
        np.testing.assert_allclose(cv.z, loo.z, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(cv.rmse, loo.rmse, rtol=1e-10)


def test_folds_over_draws_equal_dense_conditionals_averaged_by_hand():
    """Group folds, averaged over 5 draws: the mixture mean, variance (law of total variance)
    and PIT computed here from dense solves on the kept runs of each fold: the weights', and
    the outputs' over all m x l_sim outputs (the held-out outputs' variance had counted the
    projection noise 1/(lam_sim lamWOs) on top of the residual 1/lamWOs: up to 3% too wide
    here)."""
    emu = vector_fit()
    labels = np.arange(emu.m) % 4
    cv = cross_validate(emu, folds=labels, n_draws=5)
    means, varis, pits = [], [], []
    std = emu.standardizer
    y_std = std.y_to_std(emu.y)
    for i in cv.draw_index:
        prm = {k: emu.draws[k][i] for k in PARAMS}
        mw, vw = np.empty((emu.m, emu.p_u)), np.empty((emu.m, emu.p_u))
        my, vy = np.empty((emu.m, emu.l_sim)), np.empty((emu.m, emu.l_sim))
        for g in range(4):
            F = np.flatnonzero(labels == g)
            mw[F], vw[F] = _held_out_by_solve(emu, prm, F)
            my[F], vy[F] = _held_out_outputs_by_solve(emu, prm, F)
        np.testing.assert_allclose(my, mw @ emu.K.T, atol=1e-9)  # the weights' mean, through K
        means.append(my)
        varis.append(vy)
        pits.append(ndtr((y_std - my) / np.sqrt(vy)))
    means, varis = np.array(means), np.array(varis)
    mean = std.y_from_std(means.mean(0))
    var = std.var_from_std(varis.mean(0) + means.var(0))
    np.testing.assert_allclose(cv.mean, mean, rtol=1e-9, atol=1e-9 * np.abs(mean).max())
    np.testing.assert_allclose(cv.var, var, rtol=1e-7)
    np.testing.assert_allclose(cv.pit, np.mean(pits, axis=0), atol=1e-9)
    np.testing.assert_array_equal(cv.folds, labels)


def test_k_fold_with_m_folds_is_leave_one_out():
    emu = vector_fit()
    loo = cross_validate(emu, n_draws=10)
    kf = cross_validate(emu, folds=emu.m, n_draws=10, seed=0)
    np.testing.assert_allclose(kf.mean, loo.mean, rtol=1e-10)
    np.testing.assert_allclose(kf.var, loo.var, rtol=1e-10)
    five = cross_validate(emu, folds=5, n_draws=10, seed=0)
    assert sorted(np.bincount(five.folds)) == [7, 7, 7, 7, 8]
    # holding out more runs at once cannot make the prediction more certain on average
    assert np.mean(five.var) > np.mean(loo.var)


def test_loo_over_draws_is_calibrated_on_a_gp_sample():
    """Runs drawn from a GP with the emulator's own structure (one component, known betaU,
    lamUz, nugget): the LOO PITs over the posterior draws of a fit are near uniform, the 90 %
    coverage within binomial error (m = 80 runs: sd 0.034; |coverage - 0.9| < 0.12 is 3.5 sd)."""
    rng = np.random.default_rng(5)
    m = 80
    x, t = rng.uniform(size=(m, 1)), rng.uniform(size=(m, 1))
    z = np.hstack([x, t])
    C = correlation(z, None, np.array([3.0, 2.0])) + 1e-3 * np.eye(m)
    y = np.linalg.cholesky(C) @ rng.standard_normal(m)
    data = gpmsa.SimData(x=x, t=t, y=y[:, None], x_names=["x"], t_names=["t"])
    emu = gpmsa.fit(data, n_iter=300, seed=1, tune_rounds=10)
    cv = cross_validate(emu, n_draws=100)
    assert abs(cv.coverage(0.9) - 0.9) < 0.12
    assert 0.3 < np.mean(cv.pit) < 0.7
    assert cv.pit.shape == (m, 1) and cv.draw_index.size == 100


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"folds": 1}, r"folds must be an integer in \[2, m\]"),
        ({"folds": 10_000}, r"folds must be an integer in \[2, m\]"),
        ({"folds": np.zeros(3)}, r"one label per run \(shape \(36,\)\)"),
        ({"folds": np.zeros(36)}, "at least two different labels"),
        ({"n_draws": -1}, "n_draws must be"),
        ({"seed": "x"}, r"seed must be .* got 'x'"),  # refused even where leave-one-out needs none
    ],
)
def test_bad_input(kw, match):
    with pytest.raises(GPMSAError, match=match):
        cross_validate(vector_fit(), **kw)


def test_no_draws_kept():
    with pytest.raises(GPMSAError, match="kept none"):
        cross_validate(two_param_emulator())
    with pytest.raises(GPMSAError, match=r"level must be a number in \(0, 1\)"):
        cross_validate(two_param_emulator(), draws=False).coverage(1.0)


def test_a_cross_validation_beyond_the_memory_limit_is_refused_before_its_factors(monkeypatch):
    """Per draw it holds each component's m x m Cholesky factor and the precision: checked against
    gpmsa.limits.MAX_MEMORY_BYTES first, as the other predictive functions are (was unchecked)."""
    emu = two_param_emulator()
    need = 8.0 * (emu.p_u + 3) * emu.m**2
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", need - 1)
    with pytest.raises(gpmsa.ResourceLimitError, match=r"cross_validate: \d+ covariance factors"):
        cross_validate(emu, draws=False)
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", need)
    assert np.all(np.isfinite(cross_validate(emu, draws=False).mean))
