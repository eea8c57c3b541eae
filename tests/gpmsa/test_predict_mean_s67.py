"""Emulator.predict_mean (session 67): the mean alone, to the last bit what ``predict`` returns
as its mean, at the point estimate and over draws, for every kind of emulator; the arguments
checked as ``predict`` checks them."""

import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError


def _fit(data, **kw) -> gpmsa.Emulator:
    """A short untuned fit: it has draws (not converged; the equality needs none)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(data, n_iter=30, tune=False, seed=0, **kw)


@cache
def _cases() -> dict:
    """Name -> (emulator, x, t) of each kind: scalar and functional output, p = 0, categorical
    inputs, a mean basis, several components."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(0.0, 2.0, (14, 1)), rng.uniform(0.0, 1.0, (14, 1))
    s = np.linspace(0.0, 1.0, 6)
    y_fun = np.sin(2.0 * x) * (1.0 + s) + np.outer(t[:, 0] ** 2, s**2)
    kinds = np.arange(14.0)[:, None] % 3
    xc, tc = rng.uniform(0.1, 1.9, (5, 1)), rng.uniform(0.1, 0.9, (5, 1))
    return {
        "scalar": (_fit(gpmsa.SimData(x, t, np.sin(x) + t**2)), xc, tc),
        "functional": (_fit(gpmsa.SimData(x, t, y_fun, index=s), n_pc=3), xc, tc),
        "p0": (_fit(gpmsa.SimData(t=t, y=np.sin(3 * t))), None, tc),
        "categorical": (
            _fit(gpmsa.SimData(np.hstack([x, kinds]), t, np.sin(x) + t + kinds, x_categorical=[1])),
            np.hstack([xc, [[0.0], [1.0], [2.0], [1.0], [0.0]]]),
            tc,
        ),
        "mean_basis": (_fit(gpmsa.SimData(x, t, 3 * x + 2 * t), mean_basis="linear"), xc, tc),
    }


@pytest.mark.parametrize("name", ["scalar", "functional", "p0", "categorical", "mean_basis"])
def test_predict_mean_is_predicts_mean_to_the_last_bit(name):
    emu, x, t = _cases()[name]
    assert emu.n_draws > 0
    assert (emu.p_u >= 3, emu.l_sim > 1) == ((name == "functional",) * 2)
    assert (emu.p == 0, bool(emu.categorical)) == (name == "p0", name == "categorical")
    assert (emu.mean_basis is not None) == (name == "mean_basis")
    for kw in ({}, {"draws": True}, {"draws": True, "n_draws": 4}):
        mean = emu.predict_mean(x, t, **kw)
        for resid in (True, False):
            want, _ = emu.predict(x, t, resid=resid, **kw)
            assert mean.shape == want.shape == (t.shape[0], emu.l_sim)
            np.testing.assert_array_equal(mean, want)


def test_predict_mean_of_an_emulator_from_params_and_one_point():
    rng = np.random.default_rng(3)
    x, t = rng.random((18, 1)) * 4, rng.random((18, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.cos(x) + t**2, x_names=["x"], t_names=["t"])
    prm = {"betaU": [[2.0], [0.5]], "lamUz": [1.2], "lamWs": [2000.0], "lamWOs": [5000.0]}
    emu = gpmsa.Emulator.from_params(sim, prm)
    np.testing.assert_array_equal(emu.predict_mean(1.5, 0.5), emu.predict(1.5, 0.5)[0])
    with pytest.raises(GPMSAError, match="no posterior draws.*pass draws=False"):
        emu.predict_mean(1.5, 0.5, draws=True)


def test_predict_mean_checks_its_arguments_as_predict_does():
    emu, x, t = _cases()["scalar"]
    bad = [
        ({"draws": "yes"}, "draws"),
        ({"draws": True, "n_draws": 0}, "n_draws"),
        ({"n_draws": 2.5}, "n_draws"),  # checked where draws=False leaves it unused, as predict
    ]
    for kw, arg in bad:
        with pytest.raises(GPMSAError, match=arg) as got:
            emu.predict_mean(x, t, **kw)
        with pytest.raises(GPMSAError) as want:
            emu.predict(x, t, **kw)
        assert str(got.value) == str(want.value)
    lo, hi = emu.domain[emu.x_names[0]]
    for xb in ([[hi + (hi - lo)]], [[1.0], [1.0]], [[1.0, 2.0]]):  # far outside; rows; columns
        with pytest.raises(GPMSAError) as got:
            emu.predict_mean(xb, [[0.5], [0.5], [0.5]])
        with pytest.raises(GPMSAError) as want:
            emu.predict(xb, [[0.5], [0.5], [0.5]])
        assert str(got.value) == str(want.value)
    with pytest.raises(TypeError, match="resid"):  # the mean does not depend on it
        emu.predict_mean(x, t, resid=False)


def test_predict_mean_warns_of_extrapolation_at_the_callers_line():
    emu, _, _ = _cases()["scalar"]
    lo, hi = emu.domain[emu.x_names[0]]
    for kw in ({}, {"draws": True, "n_draws": 2}):
        with pytest.warns(UserWarning, match="extrapolates") as rec:
            emu.predict_mean([[hi + 0.05 * (hi - lo)]], [[0.5]], **kw)
        assert [w.filename for w in rec] == [__file__]
        with pytest.warns(UserWarning, match="extrapolates") as rec:
            emu.predict([[hi + 0.05 * (hi - lo)]], [[0.5]], **kw)
        assert [w.filename for w in rec] == [__file__]
