"""Emulator predictions and exact LOO against brute-force formulas; input checks."""

import numpy as np
import pytest

import gpmsa
from gpmsa.model.correlation import correlation

PARAMS = {"betaU": [[2.0], [0.5]], "lamUz": [1.2], "lamWs": [2000.0], "lamWOs": [5000.0]}


@pytest.fixture(scope="module")
def emu():
    rng = np.random.default_rng(3)
    x, t = rng.random((18, 1)) * 4, rng.random((18, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.cos(x) + t**2, x_names=["x"], t_names=["t"])
    return gpmsa.Emulator.from_params(sim, PARAMS)


def brute_predict(emu, z_new):
    """GP conditional mean/variance of w at unit-scale points, by dense solves."""
    beta = emu.params["betaU"][:, 0]
    lam_uz, lam_ws, lam_wos = (
        emu.params["lamUz"][0],
        emu.params["lamWs"][0],
        emu.params["lamWOs"][0],
    )
    S = correlation(emu.zt, None, beta) / lam_uz + np.eye(emu.m) * (1 / lam_wos + 1 / lam_ws)
    r = correlation(z_new, emu.zt, beta) / lam_uz
    mean = r @ np.linalg.solve(S, emu.w[:, 0])
    var = 1 / lam_uz - np.einsum("ij,ji->i", r, np.linalg.solve(S, r.T))
    return mean, var + 1 / lam_ws + 1 / lam_wos


def test_predict_matches_dense_conditional(emu):
    x = np.array([[0.5], [2.0], [3.7]])
    t = np.array([[0.1], [0.5], [0.9]])
    mean, var = emu.predict(x, t)
    s = emu.standardizer
    z = np.hstack([s.x_to_unit(x), s.t_to_unit(t)])
    bm, bv = brute_predict(emu, z)
    assert np.allclose(mean[:, 0], s.y_from_std(bm))
    assert np.allclose(var[:, 0], bv * s.y_sd**2)
    _, v_smooth = emu.predict(x, t, resid=False)
    p = emu.params
    assert np.allclose(var - v_smooth, (1 / p["lamWs"][0] + 1 / p["lamWOs"][0]) * s.y_sd**2)
    assert np.allclose(mean[:, 0], np.cos(x[:, 0]) + t[:, 0] ** 2, atol=0.15)


def test_loo_equals_brute_force_refits(emu):
    loo = emu.loo()
    s = emu.standardizer
    for i in (0, 7, 17):
        keep = np.arange(emu.m) != i
        beta = emu.params["betaU"][:, 0]
        p = emu.params
        nug = 1 / p["lamWOs"][0] + 1 / p["lamWs"][0]
        S = correlation(emu.zt[keep], None, beta) / p["lamUz"][0] + np.eye(emu.m - 1) * nug
        r = correlation(emu.zt[i : i + 1], emu.zt[keep], beta)[0] / p["lamUz"][0]
        m = r @ np.linalg.solve(S, emu.w[keep, 0])
        v = 1 / p["lamUz"][0] + nug - r @ np.linalg.solve(S, r)
        assert loo.mean[i, 0] == pytest.approx(s.y_from_std(np.array([m]))[0], rel=1e-9)
        assert loo.var[i, 0] == pytest.approx(v * s.y_sd**2, rel=1e-9)
    assert np.allclose(loo.z, (emu.y - loo.mean) / np.sqrt(loo.var))


def test_predict_input_errors(emu):
    with pytest.raises(gpmsa.GPMSAError, match="x must be finite"):
        emu.predict([[np.nan]], [[0.5]])
    with pytest.raises(gpmsa.GPMSAError, match="same number of rows"):
        emu.predict([[1.0], [2.0]], [[0.1], [0.2], [0.3]])
    with pytest.raises(
        gpmsa.GPMSAError, match=r"x reaches \[9, 9\], outside the emulator's domain"
    ):
        emu.predict([[9.0]], [[0.5]])
    lo, hi = emu.domain["x"]
    with pytest.warns(UserWarning, match="extrapolates"):
        emu.predict([[hi + 0.05 * (hi - lo)]], [[0.5]])
    with pytest.raises(gpmsa.GPMSAError, match="no posterior draws"):
        emu.predict([[1.0]], [[0.5]], draws=True)
    mean, _ = emu.predict([[1.0]], [[0.1], [0.2], [0.3]])  # one x row broadcasts
    assert mean.shape == (3, 1)


def test_a_number_is_one_point_for_a_one_column_input(emu):
    """``predict(1.0, 0.5)`` and ``emulator_prediction(emu, 1.0, 0.5)`` raised "x must be a
    non-empty 2-D array, got shape ()" where ``calibrate`` and ``calibrated_predict`` take a
    number for one x; a number is one point of a one-column input, as [[1.0]] is."""
    np.testing.assert_array_equal(emu.predict(1.0, 0.5)[1], emu.predict([[1.0]], [[0.5]])[1])
    one = gpmsa.emulator_prediction(emu, 1.0, 0.5, draws=False, seed=1)
    np.testing.assert_array_equal(one.y, gpmsa.emulator_prediction(
        emu, [[1.0]], [[0.5]], draws=False, seed=1).y)  # fmt: skip
    with pytest.raises(gpmsa.GPMSAError, match="x must be finite"):
        emu.predict(np.nan, 0.5)


def test_from_params_shape_errors(emu):
    rng = np.random.default_rng(0)
    sim = gpmsa.SimData(x=rng.random(10), t=rng.random(10), y=rng.random(10))
    with pytest.raises(gpmsa.GPMSAError, match=r"params needs 'lamWOs'"):
        gpmsa.Emulator.from_params(sim, {k: v for k, v in PARAMS.items() if k != "lamWOs"})
    with pytest.raises(gpmsa.GPMSAError, match=r"params\['betaU'\] must have shape \(2, 1\)"):
        gpmsa.Emulator.from_params(sim, {**PARAMS, "betaU": [1.0, 2.0, 3.0]})
    with pytest.raises(gpmsa.GPMSAError, match=r"params\['lamUz'\] must be finite and > 0"):
        gpmsa.Emulator.from_params(sim, {**PARAMS, "lamUz": [-1.0]})
    with pytest.raises(gpmsa.GPMSAError, match=r"params\['lamUz'\] must hold real numbers"):
        gpmsa.Emulator.from_params(sim, {**PARAMS, "lamUz": np.array([1.2 + 0j])})


def test_complex_prediction_inputs_are_refused_not_cast(emu):
    with pytest.raises(gpmsa.GPMSAError, match="x must hold real numbers, got complex values"):
        emu.predict(np.array([[1.0 + 1j]]), [[0.5]])
    with pytest.raises(gpmsa.GPMSAError, match="t must hold real numbers"):
        emu.predict([[1.0]], np.array([[0.5 + 0j]]))


@pytest.mark.parametrize(
    ("n_draws", "match"),
    [(0, "n_draws must be an integer >= 1, got 0"), (-5, "got -5"), (2.5, "got 2.5"),
     (float("nan"), "got nan"), ("3", "got '3'"), (True, "got True")],
)  # fmt: skip
def test_predict_n_draws_is_a_count(n_draws, match):
    from _predict_cases import vector_fit

    with pytest.raises(gpmsa.GPMSAError, match=match):
        vector_fit().predict([[0.5]], [[0.5]], draws=True, n_draws=n_draws)


def test_predict_with_more_draws_than_kept_uses_all_of_them():
    """A huge n_draws (10**18 allocated an index array of 8 EB) means every retained draw."""
    from _predict_cases import vector_fit

    emu = vector_fit()
    every = emu.predict([[0.5]], [[0.5]], draws=True)
    for n in (emu.n_draws, 10**18):
        np.testing.assert_array_equal(emu.predict([[0.5]], [[0.5]], draws=True, n_draws=n)[0],
                                      every[0])  # fmt: skip


def test_the_extrapolation_warning_names_the_callers_line(emu):
    """At the point estimate (the default) the warning named emulator.py, not the caller: it
    pointed into gpmsa, and under Python's default filter (once per location) a second call
    site that extrapolated was not warned about."""
    lo, hi = emu.domain["x"]
    with pytest.warns(UserWarning, match="extrapolates") as rec:
        emu.predict([[hi + 0.05 * (hi - lo)]], [[0.5]])
    assert [w.filename for w in rec] == [__file__]
