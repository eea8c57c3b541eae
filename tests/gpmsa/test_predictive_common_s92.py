"""Exact checks of ``calibrated_predict`` and the shared helpers of ``gpmsa.predictive._common``
(session 92's mutation testing of gpmsa/predictive/_common.py and calibrated.py): on a tiny
emulator at fixed parameters, each mixture component is ``Emulator.predict`` at one theta, the
weights are those of the draws or of the grid's nodes, and the moments, CDF and quantiles follow
by hand."""

import dataclasses
import warnings
from types import SimpleNamespace

import numpy as np
import pytest
from _predict_cases import four_run_data, four_run_emulator
from scipy.special import ndtr, ndtri

import gpmsa
from gpmsa import GPMSAError
from gpmsa.calibration.posterior import GridMarginal
from gpmsa.predictive import CalibratedPrediction

X2 = [[0.2], [0.8]]


def _components(emu, thetas, resid=True):
    """Emulator.predict at X2 and each theta: means and variances (K, 2, 1)."""
    out = [emu.predict(X2, np.full((2, 1), th), resid=resid) for th in thetas]
    return np.array([m for m, _ in out]), np.array([v for _, v in out])


# --- calibrated_predict: the draws' mixture ----------------------------------------------------
@pytest.mark.parametrize("noise", [False, True])
def test_draws_mixture_is_the_evenly_spaced_draws_components_with_their_lamos(noise):
    """Five draws, n_theta=3: draws 0, 2, 4, weights 1/3; noise adds y_sd^2 / lamOs_k (that
    draw's own lamOs); mean and variance by the law of total variance."""
    emu = four_run_emulator()
    t = np.array([0.1, 0.3, 0.5, 0.7, 0.9])
    lam = np.array([1.0, 2.0, 4.0, 8.0, 16.0])
    post = gpmsa.Posterior({"t": t, "lamOs": lam})
    p = gpmsa.calibrated_predict(emu, post, X2, n_theta=3, noise=noise)
    mean, var = _components(emu, t[[0, 2, 4]])
    if noise:
        var = var + emu.standardizer.y_sd**2 / lam[[0, 2, 4]][:, None, None]
    np.testing.assert_allclose(p.weights, [1 / 3] * 3, rtol=1e-15)
    np.testing.assert_allclose(p.comp_mean, mean, rtol=1e-12)
    np.testing.assert_allclose(p.comp_var, var, rtol=1e-12)
    m = mean.mean(axis=0)
    np.testing.assert_allclose(p.mean, m, rtol=1e-12)
    np.testing.assert_allclose(p.var, (var + (mean - m) ** 2).mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(p.sd, np.sqrt(p.var), rtol=1e-15)
    np.testing.assert_array_equal(p.x, X2)


def test_noise_takes_only_the_used_draws_lamos():
    """A bad lamOs on a draw that n_theta skips is not read: only the used draws' lamOs are."""
    emu = four_run_emulator()
    post = gpmsa.Posterior({"t": np.array([0.1, 0.3, 0.5]), "lamOs": np.array([2.0, -1.0, 4.0])})
    p = gpmsa.calibrated_predict(emu, post, X2, n_theta=2, noise=True)
    _, var = _components(emu, [0.1, 0.5])
    var = var + emu.standardizer.y_sd**2 / np.array([2.0, 4.0])[:, None, None]
    np.testing.assert_allclose(p.comp_var, var, rtol=1e-12)


def _grid_posterior(info=None):
    """t on nodes (0, 0.25, 0.5, 1), density (1, 2, 1, 0): trapezoid weights (1/8, 1/4, 3/8,
    1/4), so the components are the first three nodes with weights (1/8, 1/2, 3/8)."""
    g = GridMarginal.from_log_density(np.array([0.0, 0.25, 0.5, 1.0]),
                                      np.array([0.0, np.log(2.0), 0.0, -np.inf]))  # fmt: skip
    return gpmsa.Posterior({"t": np.array([0.9, 0.95])}, grids={"t": g}, info=info)


@pytest.mark.parametrize("noise", [False, True])
def test_grid_mixture_is_the_live_nodes_with_the_trapezoid_mass(noise):
    """A one-parameter grid: the nodes carrying mass, weights w_i f_i normalised; noise adds
    y_sd^2 E[1/lamOs | theta_i] from info["expected_inv_lamOs"] at those nodes."""
    emu = four_run_emulator()
    inv = [0.5, 0.25, 1.0, 2.0]
    p = gpmsa.calibrated_predict(emu, _grid_posterior({"expected_inv_lamOs": inv}), X2,
                                 noise=noise)  # fmt: skip
    np.testing.assert_allclose(p.weights, [0.125, 0.5, 0.375], rtol=1e-14)
    mean, var = _components(emu, [0.0, 0.25, 0.5])
    if noise:
        var = var + emu.standardizer.y_sd**2 * np.array(inv[:3])[:, None, None]
    np.testing.assert_allclose(p.comp_mean, mean, rtol=1e-12)
    np.testing.assert_allclose(p.comp_var, var, rtol=1e-12)
    w = np.array([0.125, 0.5, 0.375])
    m = np.tensordot(w, mean, axes=1)
    np.testing.assert_allclose(p.mean, m, rtol=1e-12)
    np.testing.assert_allclose(p.var, np.tensordot(w, var + (mean - m) ** 2, axes=1), rtol=1e-12)


def test_grid_without_expected_inv_lamos_and_noise_uses_the_draws():
    """noise=True on a grid posterior without info["expected_inv_lamOs"]: the draws (and their
    lamOs), equally weighted, not the grid."""
    emu = four_run_emulator()
    g = _grid_posterior().grids["t"]
    post = gpmsa.Posterior({"t": np.array([0.9, 0.7]), "lamOs": np.array([2.0, 4.0])},
                           grids={"t": g})  # fmt: skip
    p = gpmsa.calibrated_predict(emu, post, X2, noise=True)
    np.testing.assert_allclose(p.weights, [0.5, 0.5], rtol=1e-15)
    mean, var = _components(emu, [0.9, 0.7])
    np.testing.assert_allclose(p.comp_mean, mean, rtol=1e-12)
    np.testing.assert_allclose(p.comp_var, var + emu.standardizer.y_sd**2 / np.array(
        [2.0, 4.0])[:, None, None], rtol=1e-12)  # fmt: skip


# --- CalibratedPrediction: cdf, quantile, interval, repr ---------------------------------------
def _prediction():
    """A hand-made two-component mixture at two points of one output."""
    comp_mean = np.array([[[0.0], [1.0]], [[2.0], [1.5]]])
    comp_var = np.array([[[1.0], [0.25]], [[4.0], [0.25]]])
    w = np.array([0.25, 0.75])
    m = np.tensordot(w, comp_mean, axes=1)
    v = np.tensordot(w, comp_var + (comp_mean - m) ** 2, axes=1)
    return CalibratedPrediction(np.array(X2), m, v, comp_mean, comp_var, w)


def test_cdf_is_the_weighted_normal_cdfs():
    p = _prediction()
    y = np.array([[0.5], [1.2]])
    want = 0.25 * ndtr((y - p.comp_mean[0]) / np.sqrt(p.comp_var[0])) + 0.75 * ndtr(
        (y - p.comp_mean[1]) / np.sqrt(p.comp_var[1]))  # fmt: skip
    np.testing.assert_allclose(p.cdf(y), want, rtol=1e-14)
    z = (0.5 - p.comp_mean) / np.sqrt(p.comp_var)
    np.testing.assert_allclose(p.cdf(0.5), 0.25 * ndtr(z[0]) + 0.75 * ndtr(z[1]), rtol=1e-14)
    with pytest.raises(GPMSAError, match=r"y must have shape \(2, 1\)"):
        p.cdf(np.zeros((3, 1)))
    with pytest.raises(GPMSAError, match=r"y must have shape \(2, 1\)"):
        p.cdf(np.zeros((1, 2, 1)))
    with pytest.raises(GPMSAError, match="y"):
        p.cdf(np.array([[0.5], [np.nan]]))


@pytest.mark.parametrize("q", [0.05, 0.5, 0.93])
def test_quantile_inverts_the_cdf(q):
    p = _prediction()
    qq = p.quantile(q)
    np.testing.assert_allclose(p.cdf(qq), np.full((2, 1), q), atol=1e-12)
    one = CalibratedPrediction(p.x, p.comp_mean[:1][0], p.comp_var[0], p.comp_mean[:1],
                                     p.comp_var[:1], np.array([1.0]))  # fmt: skip
    want = p.comp_mean[0] + np.sqrt(p.comp_var[0]) * ndtri(q)
    np.testing.assert_allclose(one.quantile(q), want, atol=1e-12)


def test_quantile_of_a_far_tail_and_the_interval():
    """q = 1e-15: the lower end, 7.9 sd below the mean (one component: its own q-quantile)."""
    p = _prediction()
    one = CalibratedPrediction(p.x, p.comp_mean[0], p.comp_var[0], p.comp_mean[:1],
                                     p.comp_var[:1], np.array([1.0]))  # fmt: skip
    np.testing.assert_allclose(one.quantile(1e-15),
                               p.comp_mean[0] + np.sqrt(p.comp_var[0]) * ndtri(1e-15),
                               rtol=1e-9)  # fmt: skip
    lo, hi = p.interval(0.8)
    np.testing.assert_array_equal(lo, p.quantile((1.0 - 0.8) / 2.0))
    np.testing.assert_array_equal(hi, p.quantile((1.0 + 0.8) / 2.0))
    for bad in (0.0, 1.0):
        with pytest.raises(GPMSAError, match="q must lie in"):
            p.quantile(bad)
    with pytest.raises(GPMSAError, match="q"):
        p.quantile([0.5])
    with pytest.raises(GPMSAError, match="level"):
        p.interval(0.0)
    lo, hi = p.interval()  # level 0.9
    np.testing.assert_array_equal(lo, p.quantile((1.0 - 0.9) / 2.0))
    np.testing.assert_array_equal(hi, p.quantile((1.0 + 0.9) / 2.0))


def test_repr_counts_points_outputs_and_components():
    assert repr(_prediction()) == "CalibratedPrediction(2 points x 1 outputs, 2 mixture components)"
    odd = CalibratedPrediction(np.zeros(1), np.zeros(3), np.zeros(3), np.zeros((1, 3)),
                               np.ones((1, 3)), np.ones(1))  # fmt: skip
    assert repr(odd) == "CalibratedPrediction(0 points x 0 outputs, 1 mixture components)"
    with pytest.raises(dataclasses.FrozenInstanceError):
        odd.mean = np.ones(3)
    assert odd != dataclasses.replace(odd) and hash(odd) == hash(odd)  # eq=False: by identity


def test_n_theta_defaults_to_200_evenly_spaced_draws():
    emu = four_run_emulator()
    t = np.linspace(0.0, 1.0, 401)
    p = gpmsa.calibrated_predict(emu, gpmsa.Posterior({"t": t}), X2)
    assert p.weights.shape == (200,)
    mean, var = _components(emu, t[[0, 2, 400]])
    np.testing.assert_allclose(p.comp_mean[[0, 1, 199]], mean, rtol=1e-12)
    np.testing.assert_allclose(p.comp_var[[0, 1, 199]], var, rtol=1e-12)


# --- _common's helpers, directly ---------------------------------------------------------------
def test_unit_inputs_shapes_and_list_bounds():
    """Bounds given as lists are read as arrays; a 1-D row of d > 1 values is one row, a number
    one point of one column, None with no columns one empty row."""
    from gpmsa.predictive._common import unit_inputs

    native, unit = unit_inputs([[1.0, 3.0]], ["a", "b"], [0.0, 2.0], [2.0, 6.0], "x")
    np.testing.assert_array_equal(native, [[1.0, 3.0]])
    np.testing.assert_array_equal(unit, [[0.5, 0.25]])
    _, unit = unit_inputs([1.0, 3.0], ["a", "b"], [0.0, 2.0], [2.0, 6.0], "x")
    np.testing.assert_array_equal(unit, [[0.5, 0.25]])
    _, unit = unit_inputs(1.5, ["a"], [1.0], [3.0], "x")
    np.testing.assert_array_equal(unit, [[0.25]])
    _, unit = unit_inputs([1.5, 2.0], ["a"], [1.0], [3.0], "x")
    np.testing.assert_array_equal(unit, [[0.25], [0.5]])
    native, unit = unit_inputs(None, [], np.empty(0), np.empty(0), "x")
    assert native.shape == unit.shape == (1, 0)
    native, unit = unit_inputs(np.empty((2, 0)), [], np.empty(0), np.empty(0), "x")
    assert native.shape == unit.shape == (2, 0)
    with pytest.raises(GPMSAError, match="level 0.5, never seen in training"):
        unit_inputs([[0.5]], ["a"], [0.0], [1.0], "x", levels=[(0.0, 1.0)])


def test_realization_interval_warns_below_two_over_the_tail_mass():
    """level 0.9: 2 / 0.1 = 20 realizations resolve the tails; 19 warn, naming 20 and the fix;
    the ends are numpy's quantiles at 0.05 and 0.95."""
    from gpmsa.errors import FewDrawsWarning
    from gpmsa.predictive._common import realization_interval, realization_quantile

    s = np.arange(40.0).reshape(20, 2) ** 1.5
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lo, hi = realization_interval(s, 0.9, "n_rlz")
    np.testing.assert_array_equal(lo, np.quantile(s, (1 - 0.9) / 2, axis=0))
    np.testing.assert_array_equal(hi, np.quantile(s, (1 + 0.9) / 2, axis=0))
    with pytest.warns(FewDrawsWarning, match=r"central 0.9 interval from 19 .*at least 20; "
                      r"draw more \(n_rlz\)"):  # fmt: skip
        realization_interval(s[:19], 0.9, "n_rlz")
    with pytest.warns(FewDrawsWarning, match="at least 4;"):
        realization_interval(s[:3], 0.5, "n_rlz")
    np.testing.assert_array_equal(realization_quantile(s, [0.25, 0.5]),
                                  np.quantile(s, [0.25, 0.5], axis=0))  # fmt: skip


def test_rng_of_keeps_a_generator_and_seeds_a_new_one():
    from gpmsa.predictive._common import rng_of

    g = np.random.default_rng(5)
    assert rng_of(g) is g
    assert rng_of(5).random() == np.random.default_rng(5).random()


def test_mvn_factor_cholesky_jitter_and_eigen_fallback():
    """A positive definite cov: its Cholesky factor (jitter 1e-12 of the mean variance); an
    indefinite one: the factor of its positive part; a zero one: a factor of ~0."""
    from gpmsa.predictive._common import mvn_factor

    cov = np.array([[4.0, 2.0], [2.0, 3.0]])
    A = mvn_factor(cov)
    np.testing.assert_allclose(A, np.linalg.cholesky(cov), rtol=1e-11)
    np.testing.assert_allclose(A @ A.T, cov + 1e-12 * 3.5 * np.eye(2), rtol=1e-15, atol=1e-15)
    A = mvn_factor(np.array([[1.0, 2.0], [2.0, 1.0]]))  # eigenvalues 3 and -1
    np.testing.assert_allclose(A @ A.T, np.full((2, 2), 1.5), rtol=1e-12)
    A = mvn_factor(np.zeros((2, 2)))
    assert np.all(np.abs(A) < 1e-100)


def test_lacks_text_and_posterior_lamos():
    from gpmsa.predictive._common import lacks_text, posterior_lamos

    assert lacks_text(["t"], ("a",)) == "posterior lacks ['t']; it has ('a',)"
    assert lacks_text(["t"], ("t[m1]",)).endswith("pass study.member_posterior(model))")
    post = gpmsa.Posterior({"t": np.arange(3.0)})
    with pytest.raises(GPMSAError, match="lacks lamOs"):
        posterior_lamos(post)
    post = gpmsa.Posterior({"t": np.arange(3.0), "lamOs": np.array([2.0, 0.0, 3.0])})
    np.testing.assert_array_equal(posterior_lamos(post, np.array([0, 2])), [2.0, 3.0])
    with pytest.raises(GPMSAError, match="finite and > 0 .*got 0.0"):
        posterior_lamos(post)


def test_check_posterior_emulator():
    from gpmsa.predictive._common import check_posterior_emulator

    emu = four_run_emulator()
    check_posterior_emulator(emu, gpmsa.Posterior({"t": np.zeros(2)}))
    own = gpmsa.Posterior({"t": np.zeros(2)}, info={"emulator_sha256": emu.model_sha256})
    check_posterior_emulator(emu, own)
    other = gpmsa.Posterior({"t": np.zeros(2)}, info={"emulator_sha256": "0" * 64, "model": "a"})
    want = r"another emulator \(study model 'a'\) \(model_sha256 000000000000\.\.\., this "
    with pytest.raises(GPMSAError, match=want + "emulator's " + emu.model_sha256[:12]):
        check_posterior_emulator(emu, other)
    with pytest.raises(GPMSAError, match="must be that gpmsa.Emulator, got object"):
        check_posterior_emulator(object(), own)


def test_paired_draws_positions_and_their_bounds():
    """info["emulator_draws"]: one integer position per sample in [0, kept); anything else is
    refused; without it, a posterior not drawn jointly is refused saying why."""
    from _calib_cases import with_draws

    from gpmsa.predictive._common import paired_draws

    emu = with_draws(four_run_emulator(), n=3)
    t = np.array([0.1, 0.2])
    for pos in ([0, 2], [2, 0]):
        got = paired_draws(emu, gpmsa.Posterior({"t": t}, info={"emulator_draws": pos}), "f")
        np.testing.assert_array_equal(got, pos)
    for bad in ([0, 3], [-1, 0], [0.0, 1.0], [0, 1, 2]):
        post = gpmsa.Posterior({"t": t}, info={"emulator_draws": bad})
        with pytest.raises(GPMSAError, match="must hold one position in the emulator's 3"):
            paired_draws(emu, post, "f")
    empty = SimpleNamespace(samples={"t": np.zeros(0)}, info={"emulator_draws": np.zeros(0, int)})
    assert paired_draws(emu, empty, "f").shape == (0,)
    with pytest.raises(GPMSAError, match="kept none"):
        paired_draws(four_run_emulator(), gpmsa.Posterior({"t": t}), "f")
    point = gpmsa.Posterior({"t": t}, info={"emulator_params": "point"})
    with pytest.raises(GPMSAError, match=r"point estimate \(emulator_params='point'\), every "
                       r"theta draw.*fitted without observations"):  # fmt: skip
        paired_draws(emu, point, "f")
    study = gpmsa.Posterior({"t": t}, info={"method": "study calibration"})
    with pytest.raises(GPMSAError, match=r"calibrate_study calibrates.*pass study\.member_post"):
        paired_draws(emu, study, "f")
    with pytest.raises(GPMSAError, match=r"records none \(info\['emulator_draws'\]\); and this"):
        paired_draws(emu, gpmsa.Posterior({"t": t}), "f")


def test_param_sets_and_draws_text():
    from _calib_cases import with_draws

    from gpmsa.predictive._common import draws_text, param_sets

    emu = with_draws(four_run_emulator(), n=5)
    idx, sets = param_sets(emu, False, 2, "f")
    np.testing.assert_array_equal(idx, [-1])
    assert sets == [emu.params] and draws_text(idx) == "point estimate"
    idx, sets = param_sets(emu, True, 3, "f")
    np.testing.assert_array_equal(idx, [0, 2, 4])
    assert draws_text(idx) == "3 draws" and draws_text([-1, 2]) == "2 draws"
    for i, s in zip(idx, sets, strict=True):
        for k in ("betaU", "lamUz", "lamWs", "lamWOs"):
            np.testing.assert_array_equal(s[k], emu.draws[k][i])
    assert len(param_sets(emu, True, None, "f")[1]) == 5
    with pytest.raises(GPMSAError, match="n_draws"):
        param_sets(emu, False, 0, "f")
    with pytest.raises(GPMSAError, match="f with draws=True needs the emulator's retained"):
        param_sets(four_run_emulator(), True, None, "f")


def test_factors_and_w_conditional_by_dense_solves():
    """Sigma_W = R / lamUz + (1 / (lam_sim lamWOs) + 1 / lamWs) I: L L^T = Sigma_W and alpha =
    Sigma_W^-1 w; the conditional mean r Sigma_W^-1 w, covariance R(z) / lamUz - r Sigma_W^-1
    r^T (joint), its diagonal (not joint)."""
    from gpmsa.model.correlation import correlation
    from gpmsa.predictive._common import factors, gp_factors, w_conditional

    emu = four_run_emulator()
    prm = {k: np.asarray(v, dtype=float) for k, v in emu.params.items()}
    S = correlation(emu.zt, None, prm["betaU"][:, 0]) / 2.0 + (1 / 50.0 + 1 / 10.0) * np.eye(4)
    [(L, alpha)] = factors(emu, prm)
    np.testing.assert_allclose(L @ L.T, S, rtol=1e-13)
    np.testing.assert_array_equal(L, np.tril(L))
    np.testing.assert_allclose(alpha, np.linalg.solve(S, emu.w[:, 0]), rtol=1e-12)
    [(L2, a2, gls)] = gp_factors(emu, prm)
    assert gls is None
    np.testing.assert_array_equal(L2, L)
    z = np.array([[0.2, 0.4], [0.9, 0.1], [0.5, 0.5]])
    r = correlation(z, emu.zt, prm["betaU"][:, 0]) / 2.0
    cov = correlation(z, None, prm["betaU"][:, 0]) / 2.0 - r @ np.linalg.solve(S, r.T)
    mean, spread = w_conditional(emu, prm, [(L, alpha, None)], z, True)
    np.testing.assert_allclose(mean[:, 0], r @ np.linalg.solve(S, emu.w[:, 0]), rtol=1e-12)
    np.testing.assert_allclose(spread[0], cov, rtol=1e-10, atol=1e-14)
    mean2, var = w_conditional(emu, prm, [(L, alpha, None)], z, False)
    np.testing.assert_array_equal(mean2, mean)
    np.testing.assert_allclose(var[:, 0], np.diag(cov), rtol=1e-10)


def test_factors_refuses_a_large_separable_emulator(monkeypatch):
    from gpmsa.model import kronecker
    from gpmsa.predictive._common import factors

    xs, ts = np.linspace(0.0, 1.0, 3), np.array([[0.1, 0.7], [0.5, 0.2], [0.9, 0.4]])
    x, t = np.repeat(xs, 3)[:, None], np.tile(ts, (3, 1))
    y = np.sin(3 * x) + t[:, :1] ** 2 + 0.3 * t[:, 1:]
    data = gpmsa.SimData(x=x, t=t, y=y, separable=[[0], [1, 2]])
    prm = {"betaU": [[1.0], [2.0], [1.0]], "lamUz": [2.0], "lamWs": [10.0], "lamWOs": [50.0]}
    emu = gpmsa.Emulator.from_params(data, prm)
    monkeypatch.setattr(kronecker, "MAX_DENSE_RUNS", 8)
    with pytest.raises(GPMSAError, match="builds the dense 9 x 9 Sigma_W"):
        factors(emu, emu.params)


@pytest.mark.parametrize("resid", [True, False])
def test_paired_draws_components_are_each_draws_own_predictive(resid, capsys):
    """draws=True: sample i's component is the predictive at the emulator parameters of draw
    info["emulator_draws"][i] (an emulator built from that draw's parameters), n_theta of the
    samples evenly spaced; repeated draws give the same component."""
    from _calib_cases import with_draws

    base = four_run_emulator()
    emu = with_draws(base, n=4)
    t = np.array([0.1, 0.3, 0.5, 0.7, 0.9])
    pos = np.array([3, 0, 1, 0, 2])
    post = gpmsa.Posterior({"t": t}, info={"emulator_draws": pos})
    p = gpmsa.calibrated_predict(emu, post, X2, draws=True, n_theta=4, resid=resid)
    used = [0, 1, 3, 4]  # evenly_spaced(5, 4)
    want_m, want_v = [], []
    for i in used:
        prm = {k: np.asarray(emu.draws[k][pos[i]]) for k in ("betaU", "lamUz", "lamWs", "lamWOs")}
        one = gpmsa.Emulator.from_params(four_run_data(), prm)
        m, v = one.predict(X2, np.full((2, 1), t[i]), resid=resid)
        want_m.append(m)
        want_v.append(v)
    np.testing.assert_allclose(p.comp_mean, want_m, rtol=1e-12)
    np.testing.assert_allclose(p.comp_var, want_v, rtol=1e-12)
    np.testing.assert_allclose(p.weights, [0.25] * 4, rtol=1e-15)
    assert capsys.readouterr().err == ""  # progress=False by default: no bar


def test_paired_draws_without_a_record_and_as_many_samples_as_draws():
    """No info["emulator_draws"], an emulator without a joint fit, as many samples as retained
    draws: refused saying it has no theta draws (not read as a joint fit's)."""
    from _calib_cases import with_draws

    from gpmsa.predictive._common import paired_draws

    emu = with_draws(four_run_emulator(), n=3)
    with pytest.raises(GPMSAError, match="fitted without observations, so it has no theta"):
        paired_draws(emu, gpmsa.Posterior({"t": np.array([0.1, 0.2, 0.3])}), "f")


def _callable_basis_emulator() -> gpmsa.Emulator:
    prm = {"betaU": [[1.0], [2.0]], "lamUz": [2.0], "lamWs": [10.0], "lamWOs": [50.0]}
    return gpmsa.Emulator.from_params(
        four_run_data(), prm, mean_basis=lambda z: np.ones((len(z), 1))
    )


def test_extended_and_gpmsa_model_only():
    """A categorical input or a mean basis each make the emulator extended; a callable basis is
    refused only where callable_basis=False (the default takes it)."""
    from _calib_cases import categorical_emulator

    from gpmsa.predictive._common import extended, gpmsa_model_only

    assert not extended(four_run_emulator())
    assert extended(categorical_emulator())
    emu = _callable_basis_emulator()
    assert extended(emu)
    gpmsa_model_only(emu, "f")
    with pytest.raises(GPMSAError, match="f supports the mean bases"):
        gpmsa_model_only(emu, "f", callable_basis=False)
    with pytest.raises(GPMSAError, match="f needs a gpmsa.Emulator, got object"):
        gpmsa_model_only(object(), "f")


@pytest.mark.parametrize("which", ["categorical", "basis"])
def test_w_conditional_of_an_extended_emulator_is_emulator_predict(which):
    """Through K and the standardizer, `w_conditional`'s mean and variance (gp_factors, no
    nugget, no residual) are ``Emulator.predict(resid=False)``'s: the categorical kernel and the
    GLS mean and its variance included."""
    from _calib_cases import categorical_emulator

    from gpmsa.predictive._common import gp_factors, unit_inputs, w_conditional

    emu = categorical_emulator() if which == "categorical" else _callable_basis_emulator()
    x, t = np.array([[0.3], [0.7], [0.1]]), np.array([[0.0], [2.0], [1.0]])
    if which == "basis":
        t = np.array([[0.2], [0.6], [0.9]])
    s = emu.standardizer
    z = np.hstack(
        [
            unit_inputs(x, emu.x_names, s.x_min, s.x_max, "x", emu.levels[:1])[1],
            unit_inputs(t, emu.t_names, s.t_min, s.t_max, "t", emu.levels[1:])[1],
        ]
    )
    prm = emu.params
    mean, var = w_conditional(emu, prm, gp_factors(emu, prm), z, False)
    pm, pv = emu.predict(x, t, resid=False)
    np.testing.assert_allclose(s.y_from_std(mean @ emu.K.T), pm, rtol=1e-10)
    np.testing.assert_allclose(s.var_from_std(var @ (emu.K**2).T), pv, rtol=1e-8)
    _, cov = w_conditional(emu, prm, gp_factors(emu, prm), z, True)
    np.testing.assert_allclose(np.diagonal(cov, axis1=1, axis2=2).T, var, rtol=1e-8, atol=1e-15)


def test_posterior_theta_is_on_the_unit_scale():
    """t in [0, 2] natively: theta 0.5 and 1.5 are 0.25 and 0.75 on the unit scale."""
    from gpmsa.predictive._common import posterior_theta

    d = four_run_data()
    data = gpmsa.SimData(x=d.x, t=2.0 * d.t, y=d.y, x_names=["x"], t_names=["t"])
    prm = {"betaU": [[1.0], [2.0]], "lamUz": [2.0], "lamWs": [10.0], "lamWOs": [50.0]}
    emu = gpmsa.Emulator.from_params(data, prm)
    np.testing.assert_allclose(posterior_theta(emu, np.array([[0.5], [1.5]])), [[0.25], [0.75]])


@pytest.mark.parametrize(("d", "jitter"), [(5e-11, 1e-10), (5e-9, 1e-8)])
def test_mvn_factor_steps_up_the_jitter_ladder(d, jitter):
    """cov = [[1, 1 + d], [1 + d, 1]] has the eigenvalue -d: the Cholesky factor of the first
    jitter (times the mean variance, 1) that makes it positive definite."""
    from gpmsa.predictive._common import mvn_factor

    cov = np.array([[1.0, 1.0 + d], [1.0 + d, 1.0]])
    A = mvn_factor(cov)
    np.testing.assert_array_equal(A, np.tril(A))
    np.testing.assert_allclose(A @ A.T, cov + jitter * np.eye(2), rtol=0, atol=1e-15)


def test_unit_inputs_refuses_a_ragged_table_by_name():
    from gpmsa.predictive._common import unit_inputs

    with pytest.raises(GPMSAError, match="x"):
        unit_inputs([[1.0, 2.0], [3.0]], ["a", "b"], [0.0, 0.0], [4.0, 4.0], "x")


def test_grid_nodes_below_1e_12_of_the_largest_mass_are_dropped():
    """201 nodes of mass ~1/200: a node of relative density 1e-11 is kept (mass 5e-14 > 1e-12 x
    5e-3), one of 1e-13 is dropped; the weights are the kept trapezoid masses, normalised."""
    emu = four_run_emulator()
    nodes = np.linspace(0.0, 1.0, 201)
    log_f = np.zeros(201)
    log_f[50], log_f[150] = np.log(1e-11), np.log(1e-13)
    g = GridMarginal.from_log_density(nodes, log_f)
    p = gpmsa.calibrated_predict(emu, gpmsa.Posterior({"t": np.array([0.5])}, grids={"t": g}), X2)
    keep = np.arange(201) != 150
    w = (g.weights * g.density)[keep]
    np.testing.assert_allclose(p.weights, w / w.sum(), rtol=1e-14)
    mean, _ = _components(emu, nodes[[0, 50, 200]])
    np.testing.assert_allclose(p.comp_mean[[0, 50, 199]], mean, rtol=1e-12)


@pytest.mark.parametrize("q", [1e-6, 1.0 - 1e-6])
def test_quantile_of_a_wide_component_in_both_tails(q):
    """sd 2: the 1e-6 quantiles lie 4.75 sd = 9.5 from the mean (in sds, not output units)."""
    one = CalibratedPrediction(np.zeros((1, 1)), np.ones((1, 1)), np.full((1, 1), 4.0),
                               np.ones((1, 1, 1)), np.full((1, 1, 1), 4.0), np.ones(1))  # fmt: skip
    np.testing.assert_allclose(one.quantile(q), 1.0 + 2.0 * ndtri(q), rtol=1e-9)


def test_calibrated_predict_checks_its_posterior_options_and_memory(monkeypatch):
    """Another emulator's posterior, a non-flag draws, n_theta 0, x_new beyond the margin (the
    extrapolate default False) and a prediction above the memory limit are refused."""
    from _calib_cases import with_draws

    emu = four_run_emulator()
    post = gpmsa.Posterior({"t": np.array([0.2, 0.4])}, info={"emulator_sha256": "0" * 64})
    with pytest.raises(GPMSAError, match="drawn with another emulator"):
        gpmsa.calibrated_predict(emu, post, X2)
    post = gpmsa.Posterior({"t": np.array([0.2, 0.4])}, info={"emulator_draws": [0, 1]})
    with pytest.raises(GPMSAError, match="draws must be True or False"):
        gpmsa.calibrated_predict(emu, post, X2, draws="yes")
    with pytest.raises(GPMSAError, match="n_theta"):
        gpmsa.calibrated_predict(emu, post, X2, n_theta=0)
    with pytest.raises(GPMSAError, match="x_new"):
        gpmsa.calibrated_predict(emu, post, [[2.0]])
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", 100.0)
    with pytest.raises(gpmsa.errors.ResourceLimitError, match="predict"):
        gpmsa.calibrated_predict(with_draws(emu, n=2), post, X2, draws=True)


def test_calibrated_predict_warns_once_for_x_new_in_the_margin():
    """x_new 5 % outside the x range: one ExtrapolationWarning (check_x's), not another from
    the prediction inside."""
    emu = four_run_emulator()
    post = gpmsa.Posterior({"t": np.array([0.2, 0.4])})
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        gpmsa.calibrated_predict(emu, post, [[1.05]])
    assert len(seen) == 1, [str(w.message) for w in seen]


@pytest.mark.parametrize("q", [1e-25, 1e-300, 1.0 - 1e-16])
def test_a_quantile_beyond_nine_sds_is_found(q):
    """(Before session 92 the bisection started within 9 sds of the components and gave that
    bracket's end for q below ~1e-19 or as near 1.) The components' own q-quantiles bracket a
    mixture's: one component is inverted exactly, two far apart split the mass."""
    from gpmsa.predictive.calibrated import CalibratedPrediction

    one = CalibratedPrediction(x=np.zeros((1, 1)), mean=np.full((1, 1), 2.0),
                               var=np.full((1, 1), 4.0), comp_mean=np.full((1, 1, 1), 2.0),
                               comp_var=np.full((1, 1, 1), 4.0), weights=np.ones(1))  # fmt: skip
    np.testing.assert_allclose(one.quantile(q), [[2.0 + 2.0 * ndtri(q)]], rtol=1e-14)
    two = CalibratedPrediction(x=np.zeros((1, 1)), mean=np.full((1, 1), 5.0),
                               var=np.full((1, 1), 26.0), comp_mean=np.array([[[0.0]], [[10.0]]]),
                               comp_var=np.ones((2, 1, 1)), weights=np.full(2, 0.5))  # fmt: skip
    if q < 0.5:  # (near 1 the CDF itself is resolved to ~1e-16 only)
        # the far lower tail is the nearer component's alone, at probability q / 0.5
        np.testing.assert_allclose(two.quantile(q), [[ndtri(2 * q)]], rtol=1e-12)
