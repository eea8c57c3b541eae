"""Exact checks of ``emulator_prediction`` and ``cross_validate`` on tiny emulators at fixed
parameters (session 91's mutation testing of gpmsa/predictive/emulator_draws.py and crossval.py):
the realizations rebuilt from the seeded normal stream, the moments by dense algebra, the
boundaries of the memory estimates and of the folds."""

import dataclasses

import numpy as np
import pytest
from _calib_cases import with_draws
from _predict_cases import four_run_emulator

import gpmsa
from gpmsa import GPMSAError
from gpmsa.model.correlation import correlation
from gpmsa.predictive import CrossValidation, EmulatorPrediction

PARAMS = ("betaU", "lamUz", "lamWs", "lamWOs")


def _vector_emulator() -> gpmsa.Emulator:
    """Seven runs of three outputs (p_u = 2), one x and one t, fixed parameters."""
    rng = np.random.default_rng(4)
    x, t = rng.uniform(size=(7, 1)), rng.uniform(size=(7, 1))
    s = np.array([0.0, 0.5, 1.0])
    y = np.sin(2.0 * x) * (1.0 + s) + t * s**2
    data = gpmsa.SimData(x=x, t=t, y=y, index=s, x_names=["x"], t_names=["t"])
    prm = {"betaU": [[1.0, 2.0], [2.0, 1.0]], "lamUz": [2.0, 3.0], "lamWs": [10.0, 20.0],
           "lamWOs": [50.0]}  # fmt: skip
    return gpmsa.Emulator.from_params(data, prm, n_pc=2)


def _sigma_w(emu, prm, j):
    """Sigma_W_j of the runs (m, m): the GP, the projection noise and the nugget."""
    S = correlation(emu.zt, None, np.asarray(prm["betaU"])[:, j]) / prm["lamUz"][j]
    S[np.diag_indices(emu.m)] += 1 / (emu.lam_sim[j] * prm["lamWOs"][0]) + 1 / prm["lamWs"][j]
    return S


def _conditional(emu, prm, z, j):
    """Mean (N,) and covariance (N, N) of the smooth weight j at unit points z, by a solve."""
    beta, lam = np.asarray(prm["betaU"])[:, j], prm["lamUz"][j]
    S = _sigma_w(emu, prm, j)
    r = correlation(z, emu.zt, beta) / lam
    mean = r @ np.linalg.solve(S, emu.w[:, j])
    cov = correlation(z, None, beta) / lam - r @ np.linalg.solve(S, r.T)
    return mean, cov


def _unit(emu, x, t):
    s = emu.standardizer
    return np.hstack([s.x_to_unit(np.asarray(x, float)), s.t_to_unit(np.asarray(t, float))])


X2, T2 = [[0.2], [0.9]], [[0.4], [0.6]]


# --- emulator_prediction: the realizations from the seeded stream ------------------------------
@pytest.mark.parametrize("resid", [True, False])
def test_independent_realizations_are_the_seeded_normals_through_the_exact_moments(resid):
    """Point estimate, joint=False: w = mu + sqrt(var) e1 (e1 the first draw of the stream,
    (n_rlz, N, p_u)), y = (w K^T + e2 / sqrt(lamWOs)) y_sd + y_mean (e2 the next)."""
    emu = _vector_emulator()
    prm, n_rlz = emu.params, 3
    pred = gpmsa.emulator_prediction(emu, X2, T2, draws=False, n_rlz=n_rlz, resid=resid, seed=7)
    z = _unit(emu, X2, T2)
    mu = np.empty((2, 2))
    var = np.empty((2, 2))
    for j in range(2):
        mu[:, j], cov = _conditional(emu, prm, z, j)
        var[:, j] = np.diag(cov) + (1 / prm["lamWs"][j] if resid else 0.0)
    rng = np.random.default_rng(7)
    w = mu + np.sqrt(var) * rng.standard_normal((n_rlz, 2, 2))
    y_std = w @ emu.K.T
    if resid:
        y_std = y_std + rng.standard_normal(y_std.shape) / np.sqrt(prm["lamWOs"][0])
    s = emu.standardizer
    np.testing.assert_allclose(pred.mu_w[0], mu, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(pred.var_w[0], var, rtol=1e-10)
    np.testing.assert_allclose(pred.w, w, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(pred.y, y_std * s.y_sd + s.y_mean, rtol=1e-10, atol=1e-12)
    np.testing.assert_array_equal(pred.lamWOs, [prm["lamWOs"][0]])
    assert pred.resid is resid and pred.n_rlz == n_rlz
    np.testing.assert_array_equal(pred.draw_of, [0, 0, 0])


@pytest.mark.parametrize("resid", [True, False])
def test_joint_realizations_are_the_seeded_normals_through_the_cholesky_factor(resid):
    """joint=True: per component j, w_j = mu_j + e_j A_j^T with A_j A_j^T = cov_j + nugget I
    (e_j (n_rlz, N), drawn component after component), var_w the diagonal of that."""
    emu = _vector_emulator()
    prm, n_rlz = emu.params, 4
    pred = gpmsa.emulator_prediction(emu, X2, T2, draws=False, n_rlz=n_rlz, resid=resid,
                                     joint=True, seed=3)  # fmt: skip
    z = _unit(emu, X2, T2)
    rng = np.random.default_rng(3)
    w = np.empty((n_rlz, 2, 2))
    for j in range(2):
        mu, cov = _conditional(emu, prm, z, j)
        cov = cov + (1 / prm["lamWs"][j] if resid else 0.0) * np.eye(2)
        np.testing.assert_allclose(pred.mu_w[0, :, j], mu, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(pred.var_w[0, :, j], np.diag(cov), rtol=1e-10)
        w[:, :, j] = mu + rng.standard_normal((n_rlz, 2)) @ np.linalg.cholesky(cov).T
    y_std = w @ emu.K.T
    if resid:
        y_std = y_std + rng.standard_normal(y_std.shape) / np.sqrt(prm["lamWOs"][0])
    s = emu.standardizer
    np.testing.assert_allclose(pred.w, w, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(pred.y, y_std * s.y_sd + s.y_mean, rtol=1e-8, atol=1e-10)


def test_over_draws_the_moments_are_the_mixture_of_the_per_draw_gaussians():
    """Three draws, two realizations each: rows s * n_rlz + r belong to draw s; mean() and
    var() are the mixture's (law of total variance, the residual 1/lamWOs of each draw)."""
    emu = with_draws(_vector_emulator(), n=3, seed=5)
    pred = gpmsa.emulator_prediction(emu, X2, T2, n_rlz=2, seed=0)
    assert pred.n_rlz == 2
    np.testing.assert_array_equal(pred.draw_of, [0, 0, 1, 1, 2, 2])
    np.testing.assert_array_equal(pred.draw_index, [0, 1, 2])
    z = _unit(emu, X2, T2)
    means, varis = [], []
    for i in range(3):
        prm = {k: emu.draws[k][i] for k in PARAMS}
        mu, var = np.empty((2, 2)), np.empty((2, 2))
        for j in range(2):
            mu[:, j], cov = _conditional(emu, prm, z, j)
            var[:, j] = np.diag(cov) + 1 / prm["lamWs"][j]
        np.testing.assert_allclose(pred.mu_w[i], mu, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(pred.var_w[i], var, rtol=1e-10)
        assert pred.lamWOs[i] == emu.draws["lamWOs"][i][0]
        means.append(mu @ emu.K.T)
        varis.append(var @ (emu.K**2).T + 1 / prm["lamWOs"][0])
    means, varis = np.array(means), np.array(varis)
    s = emu.standardizer
    np.testing.assert_allclose(pred.mean(), means.mean(0) * s.y_sd + s.y_mean, rtol=1e-10)
    np.testing.assert_allclose(pred.var(), (varis.mean(0) + means.var(0)) * s.y_sd**2, rtol=1e-10)


def test_a_single_row_of_t_broadcasts_against_the_rows_of_x():
    emu = _vector_emulator()
    a = gpmsa.emulator_prediction(emu, X2, [[0.5]], draws=False, resid=False, seed=1)
    b = gpmsa.emulator_prediction(emu, X2, [[0.5], [0.5]], draws=False, resid=False, seed=1)
    np.testing.assert_array_equal(a.t, [[0.5], [0.5]])
    np.testing.assert_array_equal(a.y, b.y)


def test_interval_defaults_to_0_9_and_checks_its_level():
    pred = gpmsa.emulator_prediction(four_run_emulator(), X2, T2, draws=False, n_rlz=40, seed=2)
    lo, hi = pred.interval()
    np.testing.assert_array_equal(lo, pred.quantile(0.05))
    np.testing.assert_array_equal(hi, pred.quantile(0.95))
    with pytest.raises(GPMSAError, match=r"level must be a number in \(0, 1\)"):
        pred.interval(1.0)


def _pred_case():
    return gpmsa.emulator_prediction(four_run_emulator(), X2, T2, draws=False, n_rlz=2, seed=0)


@pytest.mark.parametrize(
    "make", [_pred_case, lambda: gpmsa.cross_validate(four_run_emulator(), draws=False)]
)
def test_the_results_are_frozen_and_hash_by_identity(make):
    """Frozen dataclasses of arrays with eq=False: no field can be reassigned, and the object
    hashes (and compares) as itself, not field by field (arrays are unhashable)."""
    res = make()
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.draw_index = np.array([0])
    assert {res: 1}[res] == 1
    assert res != dataclasses.replace(res)


def test_an_empty_prediction_prints_zero_realizations():
    empty = EmulatorPrediction(
        x=np.zeros((2, 1)), t=np.zeros((2, 1)), draw_index=np.zeros(0, int),
        mu_w=np.zeros((0, 2, 1)), var_w=np.zeros((0, 2, 1)), w=np.zeros((0, 2, 1)),
        y=np.zeros((0, 2, 1)), resid=True, K=np.ones((1, 1)), y_mean=np.zeros(1), y_sd=1.0,
        lamWOs=np.zeros(0), grid=np.zeros(1),
    )  # fmt: skip
    assert (
        repr(empty)
        == "EmulatorPrediction(2 points x 1 outputs, 0 draws x 0 realizations, resid=True)"
    )


@pytest.mark.parametrize("joint", [False, True])
def test_emulator_prediction_memory_estimate_at_its_boundary(monkeypatch, joint):
    """8 bytes x (S n_rlz N (p_u + 3 l_sim) + 3 N m + 4 p_u N^2 when joint): refused one byte
    below, run at it (S = 2 draws, n_rlz = 3, N = 2, p_u = 2, l_sim = 3, m = 7)."""
    emu = with_draws(_vector_emulator(), n=2)
    S, n_rlz, N, p_u, l_sim, m = 2, 3, 2, 2, 3, 7
    assert (emu.p_u, emu.l_sim, emu.m) == (p_u, l_sim, m)
    need = 8.0 * (S * n_rlz * N * (p_u + 3 * l_sim) + 3 * N * m + (4 * p_u * N * N if joint else 0))

    def call():
        return gpmsa.emulator_prediction(emu, X2, T2, n_rlz=n_rlz, joint=joint, seed=0)

    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", need - 1)
    with pytest.raises(gpmsa.ResourceLimitError, match=r"emulator_prediction\(n_rlz=3"):
        call()
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", need)
    assert call().y.shape == (S * n_rlz, N, l_sim)


def test_emulator_prediction_defaults(capfd):
    """draws=True, n_rlz=1, resid=True, joint=False, extrapolate=False, progress=False (no bar
    on stderr)."""
    emu = with_draws(_vector_emulator(), n=2)
    a = gpmsa.emulator_prediction(emu, X2, T2, seed=4)
    assert capfd.readouterr().err == ""
    b = gpmsa.emulator_prediction(emu, X2, T2, draws=True, n_rlz=1, resid=True, joint=False,
                                  seed=4, extrapolate=False, progress=False)  # fmt: skip
    np.testing.assert_array_equal(a.y, b.y)
    np.testing.assert_array_equal(a.draw_index, [0, 1])
    assert a.resid is True and a.y.shape == (2, 2, 3)
    lo, hi = emu.domain["x"]
    with pytest.raises(GPMSAError, match="by more than 10% of its width"):
        gpmsa.emulator_prediction(emu, [[hi + 0.5 * (hi - lo)]], [[0.5]], seed=4)


# --- cross_validate ----------------------------------------------------------------------------
def test_loo_of_a_tiny_emulator_by_dense_solves_and_its_pit():
    """Four runs, point estimate: each run's weight given the other three (a solve), the
    output the weight (one output: its projection noise is the residual), PIT = Phi(z)."""
    from scipy.special import ndtr

    emu = four_run_emulator()
    cv = gpmsa.cross_validate(emu, draws=False)
    S = _sigma_w(emu, emu.params, 0)
    w = emu.w[:, 0]
    mean, var = np.empty(4), np.empty(4)
    for i in range(4):
        k = np.setdiff1d(np.arange(4), [i])
        c = S[i, k]
        mean[i] = c @ np.linalg.solve(S[np.ix_(k, k)], w[k])
        var[i] = S[i, i] - c @ np.linalg.solve(S[np.ix_(k, k)], c)
    np.testing.assert_allclose(cv.mean_w[:, 0], mean, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(cv.var_w[:, 0], var, rtol=1e-10)
    s = emu.standardizer
    np.testing.assert_allclose(cv.mean[:, 0], mean * s.y_sd + s.y_mean[0], rtol=1e-10)
    np.testing.assert_allclose(cv.var[:, 0], var * s.y_sd**2, rtol=1e-10)
    np.testing.assert_allclose(cv.pit[:, 0], ndtr((w - mean) / np.sqrt(var)), rtol=1e-10)
    np.testing.assert_array_equal(cv.folds, [0, 1, 2, 3])
    np.testing.assert_array_equal(cv.w, emu.w)
    np.testing.assert_array_equal(cv.y, emu.y)


def test_group_folds_over_draws_are_the_mixture_of_dense_conditionals():
    """Seven runs, three outputs, folds of one and of two runs, three draws: per draw the
    held-out weights given the kept runs (a solve), the outputs through K with the residual
    (less the projection noise 1/(lam_sim lamWOs) a held-out weight holds); over the draws the
    mixture's mean and variance (law of total variance), of the weights too, and the mean PIT."""
    from scipy.special import ndtr

    emu = with_draws(_vector_emulator(), n=3, seed=2)
    labels = np.array([0, 0, 1, 2, 3, 3, 4])
    cv = gpmsa.cross_validate(emu, folds=labels)
    y_std = emu.standardizer.y_to_std(emu.y)
    mws, vws, mys, vys, pits = [], [], [], [], []
    for i in range(3):
        prm = {k: emu.draws[k][i] for k in PARAMS}
        mw, vw = np.empty((7, 2)), np.empty((7, 2))
        for j in range(2):
            S = _sigma_w(emu, prm, j)
            for g in range(5):
                F, k = np.flatnonzero(labels == g), np.flatnonzero(labels != g)
                c = S[np.ix_(F, k)]
                mw[F, j] = c @ np.linalg.solve(S[np.ix_(k, k)], emu.w[k, j])
                vw[F, j] = np.diag(S[np.ix_(F, F)] - c @ np.linalg.solve(S[np.ix_(k, k)], c.T))
        lam = prm["lamWOs"][0]
        my = mw @ emu.K.T
        vy = (vw - 1 / (emu.lam_sim * lam)) @ (emu.K**2).T + 1 / lam
        mws.append(mw), vws.append(vw), mys.append(my), vys.append(vy)
        pits.append(ndtr((y_std - my) / np.sqrt(vy)))
    mws, vws, mys, vys = map(np.array, (mws, vws, mys, vys))
    std = emu.standardizer
    np.testing.assert_allclose(cv.mean_w, mws.mean(0), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(cv.var_w, vws.mean(0) + mws.var(0), rtol=1e-9)
    np.testing.assert_allclose(cv.mean, std.y_from_std(mys.mean(0)), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(cv.var, std.var_from_std(vys.mean(0) + mys.var(0)), rtol=1e-9)
    np.testing.assert_allclose(cv.pit, np.mean(pits, axis=0), rtol=1e-9, atol=1e-12)
    assert np.all(mws.var(0) > 1e-6 * vws.mean(0))  # the draws' spread counts
    np.testing.assert_array_equal(cv.folds, labels)


def test_two_folds_is_the_smallest_k_and_holds_out_each_half():
    emu = four_run_emulator()
    cv = gpmsa.cross_validate(emu, folds=2, draws=False, seed=1)
    assert sorted(np.bincount(cv.folds)) == [2, 2]
    labelled = gpmsa.cross_validate(emu, folds=cv.folds, draws=False)
    np.testing.assert_allclose(cv.mean, labelled.mean, rtol=1e-12)
    assert repr(cv).startswith("CrossValidation(4 runs x 1 outputs, 2 folds, point estimate")


def test_coverage_counts_the_interval_ends_as_inside_and_defaults_to_0_9():
    """|pit - 0.5| <= level / 2: at level 0.5, PITs 0.25 and 0.75 (exact in binary) are
    inside, 0.2 is not."""
    pit = np.array([[0.25], [0.75], [0.5], [0.2]])
    cv = CrossValidation(
        folds=np.arange(4), draw_index=np.array([-1]), y=np.zeros((4, 1)), mean=np.zeros((4, 1)),
        var=np.ones((4, 1)), w=np.zeros((4, 1)), mean_w=np.zeros((4, 1)), var_w=np.ones((4, 1)),
        pit=pit,
    )  # fmt: skip
    assert cv.coverage(0.5) == 0.75
    far = dataclasses.replace(cv, pit=np.array([[0.04], [0.96], [0.5], [0.5]]))
    assert far.coverage() == far.coverage(0.9) == 0.5


@pytest.mark.filterwarnings("ignore:Mean of empty slice", "ignore:invalid value encountered")
def test_an_empty_cross_validation_prints_zero_runs():
    e = np.zeros(0)
    cv = CrossValidation(folds=e, draw_index=np.array([-1]), y=e, mean=e, var=e, w=e, mean_w=e,
                         var_w=e, pit=e)  # fmt: skip
    assert repr(cv).startswith("CrossValidation(0 runs x 0 outputs, leave-one-out, point estimate")


def test_cross_validate_defaults_use_the_draws_without_a_bar(capfd):
    emu = with_draws(four_run_emulator(), n=3)
    cv = gpmsa.cross_validate(emu)
    np.testing.assert_array_equal(cv.draw_index, [0, 1, 2])
    assert capfd.readouterr().err == ""
