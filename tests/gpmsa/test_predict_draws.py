"""Emulator predictions as draws (SEPIA's emulator prediction) and a joint fit's Posterior."""

import warnings

import numpy as np
import pytest
from _calib_cases import two_param_emulator
from _predict_cases import known_truth_case, mc_z, vector_fit

import gpmsa
from gpmsa import GPMSAError
from gpmsa.model.correlation import correlation
from gpmsa.predictive import emulator_prediction

X_NEW = [[0.3], [1.0], [1.7]]
T_NEW = [[-0.5], [0.1], [0.8]]


def test_moments_match_emulator_predict_exactly():
    emu = vector_fit()
    pred = emulator_prediction(emu, X_NEW, T_NEW, seed=0)
    mean, var = emu.predict(X_NEW, T_NEW, draws=True)
    np.testing.assert_allclose(pred.mean(), mean, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(pred.var(), var, rtol=1e-10)
    assert pred.draw_index.size == emu.n_draws


@pytest.mark.parametrize("resid", [True, False])
@pytest.mark.parametrize("joint", [False, True])
def test_draws_match_the_gaussian_moments_within_monte_carlo_error(resid, joint):
    """The realizations' mean and variance agree with the mixture's exact moments
    (``Emulator.predict`` over the same draws) within their Monte-Carlo standard errors."""
    emu = vector_fit()
    pred = emulator_prediction(emu, X_NEW, T_NEW, n_rlz=20, resid=resid, joint=joint, seed=1)
    assert pred.y.shape == (emu.n_draws * 20, 3, emu.l_sim)
    assert pred.w.shape == (emu.n_draws * 20, 3, emu.p_u)
    mean, var = emu.predict(X_NEW, T_NEW, draws=True, resid=resid)
    z_mean, z_var = mc_z(pred.y, mean, var)
    # 30 means and 30 variances: |z| < 4.5 fails by chance with probability < 1e-3
    assert z_mean < 4.5 and z_var < 4.5, (z_mean, z_var)


def test_joint_realizations_carry_the_gp_covariance_between_points():
    """With joint=True, realizations at two nearby points have the GP's posterior covariance
    (computed here by a dense solve); joint=False makes them independent."""
    emu = two_param_emulator()
    x, t = [[0.40], [0.45]], [[0.5, 0.5], [0.5, 0.5]]
    n = 40_000
    joint = emulator_prediction(emu, x, t, draws=False, n_rlz=n, joint=True, resid=False, seed=2)
    indep = emulator_prediction(emu, x, t, draws=False, n_rlz=n, joint=False, resid=False, seed=2)
    prm = emu.params
    z = np.hstack([emu.standardizer.x_to_unit(np.array(x)), emu.standardizer.t_to_unit(t)])
    beta, lam = prm["betaU"][:, 0], prm["lamUz"][0]
    S = correlation(emu.zt, None, beta) / lam
    S[np.diag_indices(emu.m)] += 1 / prm["lamWOs"][0] + 1 / prm["lamWs"][0]
    r = correlation(z, emu.zt, beta) / lam
    cov = correlation(z, None, beta) / lam - r @ np.linalg.solve(S, r.T)
    corr = cov[0, 1] / np.sqrt(cov[0, 0] * cov[1, 1])
    assert corr > 0.5  # nearby points: strongly correlated
    w_joint, w_indep = joint.w[:, :, 0], indep.w[:, :, 0]
    # sample correlation: standard error (1 - rho^2) / sqrt(n) < 0.004
    assert np.corrcoef(w_joint.T)[0, 1] == pytest.approx(corr, abs=0.02)
    assert abs(np.corrcoef(w_indep.T)[0, 1]) < 0.02
    np.testing.assert_allclose(w_joint.var(axis=0), np.diag(cov), rtol=0.05)


def test_same_seed_same_draws_and_point_estimate_option():
    emu = vector_fit()
    a = emulator_prediction(emu, X_NEW, T_NEW, n_draws=10, seed=5)
    b = emulator_prediction(emu, X_NEW, T_NEW, n_draws=10, seed=5)
    np.testing.assert_array_equal(a.y, b.y)
    assert a.draw_index.size == 10 and a.draw_index[0] == 0
    assert a.draw_index[-1] == emu.n_draws - 1
    point = emulator_prediction(emu, X_NEW, T_NEW, draws=False, seed=5)
    np.testing.assert_allclose(point.mean(), emu.predict(X_NEW, T_NEW)[0], rtol=1e-12)
    assert point.draw_index.tolist() == [-1]
    lo, hi = emulator_prediction(emu, X_NEW, T_NEW, n_rlz=50, seed=5).interval(0.9)
    assert np.all(lo < emu.predict(X_NEW, T_NEW)[0]) and np.all(hi > lo)


def test_a_single_row_broadcasts_and_basis_space_is_consistent():
    emu = vector_fit()
    pred = emulator_prediction(emu, [[1.0]], T_NEW, resid=False, n_draws=5, seed=0)
    assert pred.x.shape == (3, 1) and np.all(pred.x == 1.0)
    std = emu.standardizer
    np.testing.assert_allclose(pred.y, pred.w @ emu.K.T * std.y_sd + std.y_mean, rtol=1e-12)


# --- bad input ---------------------------------------------------------------------------------
def test_outside_the_domain_warns_within_the_margin_and_refuses_beyond():
    emu = vector_fit()
    lo, hi = emu.domain["x"]
    with pytest.warns(UserWarning, match=r"x: x reaches .*, outside the emulator's domain"):
        emulator_prediction(emu, [[hi + 0.05 * (hi - lo)]], [[0.0]], n_draws=2)
    with pytest.raises(GPMSAError, match=r"x reaches .* by more than 10% of its width"):
        emulator_prediction(emu, [[hi + 0.2 * (hi - lo)]], [[0.0]], n_draws=2)
    with pytest.raises(GPMSAError, match=r"t: t reaches"):
        emulator_prediction(emu, [[1.0]], [[-2.0]], n_draws=2)


@pytest.mark.parametrize(
    ("x", "t", "match"),
    [
        ([[1.0, 2.0]], [[0.0]], r"x must have 1 columns"),
        ([[1.0], [1.2], [1.3]], [[0.0], [0.1]], r"x and t need the same number of rows"),
        ([[np.nan]], [[0.0]], r"x must be finite"),
        ([[1.0]], [[0.0, 0.1]], r"t must have 1 columns"),
    ],
)
def test_shape_mismatches_name_the_problem(x, t, match):
    with pytest.raises(GPMSAError, match=match):
        emulator_prediction(vector_fit(), x, t)


def test_draws_of_an_emulator_file_that_kept_none_are_refused(tmp_path):
    path = two_param_emulator().save(tmp_path / "no_draws.gpmsa")
    emu = gpmsa.load(path)
    with pytest.raises(GPMSAError, match="kept none .* pass draws=False"):
        emulator_prediction(emu, [[0.5]], [[0.5, 0.5]])
    pred = emulator_prediction(emu, [[0.5]], [[0.5, 0.5]], draws=False, n_rlz=3, seed=0)
    assert pred.y.shape == (3, 1, 1)


@pytest.mark.parametrize("loaded", [False, True])
def test_emulator_predict_and_to_arviz_without_draws_name_both_sources(tmp_path, loaded):
    """Emulator.predict(draws=True) and to_arviz on an emulator that kept no draws: the message
    is true of one built by from_params and of one read from a file saved without draws."""
    emu = two_param_emulator()
    if loaded:
        emu = gpmsa.load(emu.save(tmp_path / "no_draws.gpmsa"))
    want = (
        r"no posterior draws \(built by Emulator.from_params, or read from a file without draws\)"
    )
    with pytest.raises(GPMSAError, match=want + r"; pass draws=False"):
        emu.predict([[0.5]], [[0.5, 0.5]], draws=True)
    with pytest.raises(GPMSAError, match=want):
        emu.to_arviz()


@pytest.mark.parametrize(
    ("kw", "match"),
    [({"n_rlz": 0}, "n_rlz must be an integer >= 1"), ({"n_draws": 0}, "n_draws must be"),
     ({"seed": "x"}, "seed must be None, an integer or a numpy Generator"),
     ({"seed": -1}, r"seed=-1 is out of range")],
)  # fmt: skip
def test_bad_settings(kw, match):
    with pytest.raises(GPMSAError, match=match):
        emulator_prediction(vector_fit(), X_NEW, T_NEW, **kw)


@pytest.mark.parametrize(
    ("kw", "match"),
    [({"n_rlz": 10**9}, r"emulator_prediction\(n_rlz=1000000000, joint=False\) at 3 points"),
     ({"x": np.full((10**5, 1), 1.0), "t": [[0.1]], "joint": True},
      r"emulator_prediction\(n_rlz=1, joint=True\) at 100000 points")],
)  # fmt: skip
def test_huge_requests_are_refused_before_allocating(kw, match):
    """n_rlz=10**9 or 10**5 points drawn jointly asked numpy for terabytes (MemoryError)."""
    args = {"x": X_NEW, "t": T_NEW, **kw}
    with pytest.raises(gpmsa.ResourceLimitError, match=match + ".*gpmsa.limits.MAX_MEMORY_BYTES"):
        emulator_prediction(vector_fit(), seed=0, **args)


def test_complex_inputs_are_refused_not_cast():
    with pytest.raises(GPMSAError, match="x must hold real numbers, got complex values"):
        emulator_prediction(vector_fit(), np.array(X_NEW) + 0j, T_NEW)


# --- a joint fit's calibration draws as a Posterior --------------------------------------------
def test_calibration_posterior_of_a_joint_fit():
    emu, *_ = known_truth_case()
    post = gpmsa.calibration_posterior(emu)
    assert isinstance(post, gpmsa.Posterior)
    assert post.names == ("t", "lamOs", "betaV", "lamVz")  # as gpmsa.calibrate names them
    np.testing.assert_array_equal(post.samples["t"], emu.calibration["theta_native"][:, 0])
    assert post.mean("t") == pytest.approx(emu.theta_summary()["t"]["mean"], rel=1e-12)
    assert post.chains["t"].shape == (1, emu.n_draws)
    assert "ess" in post.summary()["t"]
    assert post.info["method"] == "joint fit" and post.info["discrepancy"] == "linear"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        idata = post.to_arviz()
    assert set(idata.posterior.data_vars) == {"t", "lamOs", "lamVz", "betaV"}


def test_calibration_posterior_needs_a_joint_fit():
    with pytest.raises(GPMSAError, match="fitted without observations"):
        gpmsa.calibration_posterior(vector_fit())


@pytest.mark.parametrize("not_an_emulator", [{}, None, gpmsa.Posterior({"a": [1.0, 2.0]})])
def test_the_predictive_functions_name_a_missing_emulator(not_an_emulator):
    for what, call in {
        "emulator_prediction": lambda e: gpmsa.emulator_prediction(e, [[0.5]], [[0.5]]),
        "sensitivity": gpmsa.sensitivity,
        "cross_validate": gpmsa.cross_validate,
    }.items():
        with pytest.raises(GPMSAError, match=f"{what} needs a gpmsa.Emulator, got"):
            call(not_an_emulator)


def test_a_table_of_inputs_is_read_by_its_column_names():
    """A pandas DataFrame's columns are the emulator's names in any order, never read by
    position; other names are refused."""
    pd = pytest.importorskip("pandas")
    emu = two_param_emulator()
    ordered = pd.DataFrame({"a": [0.2, 0.6], "b": [0.8, 0.4]})
    swapped = ordered[["b", "a"]]
    means = [emu.predict([[0.5]], t)[0] for t in (ordered, swapped)]
    np.testing.assert_array_equal(*means)
    draws = [emulator_prediction(emu, [[0.5]], t, draws=False, seed=0).mean() for t in
             (ordered, swapped)]  # fmt: skip
    np.testing.assert_array_equal(*draws)
    for call in (lambda t: emu.predict([[0.5]], t), lambda t: emulator_prediction(emu, [[0.5]], t)):
        why = r"t has the columns \['a', 'c'\]; expected \['a', 'b'\]"
        with pytest.raises(GPMSAError, match=why):
            call(ordered.rename(columns={"b": "c"}))


def test_an_interval_from_too_few_realizations_warns_that_it_is_too_narrow():
    emu = vector_fit()
    one = emulator_prediction(emu, X_NEW, T_NEW, n_draws=1, seed=0)
    why = r"central 0.9 interval from 1 realization\(s\) is too narrow: its tails need at least 20"
    with pytest.warns(UserWarning, match=why):
        lo, hi = one.interval(0.9)
    np.testing.assert_array_equal(lo, hi)  # what the warning is about: width 0
    enough = emulator_prediction(emu, X_NEW, T_NEW, n_draws=5, n_rlz=4, seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        enough.interval(0.9)  # 20 realizations: no warning
