"""Session 73 walkthrough: the plain emulator predictions follow the library's x rule.

Before: ``Emulator.predict`` (and ``predict_mean``) and ``gpmsa.emulator_prediction`` refused
inputs more than 10 % of a column's width outside the domain with no option to allow them
(``calibrate``, ``calibrated_predict`` and ``full_prediction`` take ``extrapolate=True``);
``predict``'s error named no argument ("v reaches [1.5, 1.5], outside ...") and its warning
nothing at all ("predict() extrapolates beyond the training domain"); ``full_prediction``
named ``obs``'s x "x_obs". Now each names the argument, the column, its values and the domain,
points at ``extrapolate=True`` and takes it.
"""

from __future__ import annotations

import re
import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa


@cache
def _emulator() -> gpmsa.Emulator:
    rng = np.random.default_rng(3)
    x, t = rng.uniform(0, 1, (25, 1)), rng.uniform(0, 1, (25, 1))
    data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t, x_names=["v"], t_names=["a"])
    emu = gpmsa.fit(data, n_iter=40, tune=False, seed=1, progress=False)
    return emu


def _domain(emu, name: str) -> str:
    lo, hi = emu.domain[name]
    return re.escape(f"[{lo:.6g}, {hi:.6g}]")


def _quiet(fn, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*args, **kwargs)


def test_predict_refuses_far_inputs_by_argument_column_values_and_domain():
    emu = _emulator()
    for call in (emu.predict, emu.predict_mean):
        with pytest.raises(
            gpmsa.GPMSAError,
            match=rf"^x: v reaches \[1.5, 1.5\], outside the emulator's domain {_domain(emu, 'v')}"
            r" by more than 10% of its width; pass extrapolate=True to allow it$",
        ):
            call([[1.5]], [[0.5]])
        far_t = rf"^t: a reaches \[-0.5, 0.5\], outside the emulator's domain {_domain(emu, 'a')}"
        with pytest.raises(gpmsa.GPMSAError, match=far_t):
            call([[0.5], [0.5]], [[-0.5], [0.5]], draws=True)
        with pytest.raises(gpmsa.GPMSAError, match="extrapolate must be"):
            call([[0.5]], [[0.5]], extrapolate="yes")


def test_predict_extrapolate_true_warns_at_the_callers_line_and_predicts():
    emu = _emulator()
    x, t = [[1.5], [0.5]], [[0.5], [1.4]]
    for draws in (False, True):
        with pytest.warns(gpmsa.ExtrapolationWarning) as rec:
            mean, var = emu.predict(x, t, draws=draws, extrapolate=True)
        assert [w.filename for w in rec] == [__file__]
        assert re.fullmatch(
            rf"x: v reaches \[0.5, 1.5\], outside the emulator's domain {_domain(emu, 'v')} by "
            r"more than 10% of its width; the emulator extrapolates there",
            str(rec[0].message),
        )
        assert np.all(np.isfinite(mean)) and np.all(var > 0)
        only = _quiet(emu.predict_mean, x, t, draws=draws, extrapolate=True)
        assert np.array_equal(only, mean)
    inside, allowed = emu.predict([[0.5]], [[0.5]]), emu.predict([[0.5]], [[0.5]], extrapolate=True)
    assert all(np.array_equal(a, b) for a, b in zip(inside, allowed, strict=True))


def test_predict_within_the_margin_names_the_column_values_and_domain():
    emu = _emulator()
    lo, hi = emu.domain["v"]
    x = hi + 0.05 * (hi - lo)
    with pytest.warns(gpmsa.ExtrapolationWarning) as rec:
        emu.predict([[x]], [[0.5]])
    assert [w.filename for w in rec] == [__file__]
    assert str(rec[0].message) == (
        f"x: v reaches [{x:.6g}, {x:.6g}], outside the emulator's domain [{lo:.6g}, {hi:.6g}]; "
        "the emulator extrapolates there"
    )


def test_emulator_prediction_takes_extrapolate():
    emu = _emulator()
    x, t = [[1.5]], [[0.5]]
    with pytest.raises(gpmsa.GPMSAError, match=r"^x: v reaches .* pass extrapolate=True to allow"):
        gpmsa.emulator_prediction(emu, x, t, seed=0)
    with pytest.warns(gpmsa.ExtrapolationWarning, match=r"^x: v reaches .* extrapolates there$"):
        pred = gpmsa.emulator_prediction(emu, x, t, seed=0, extrapolate=True)
    mean, var = _quiet(emu.predict, x, t, draws=True, extrapolate=True)
    np.testing.assert_allclose(pred.mean(), mean, rtol=1e-10)
    np.testing.assert_allclose(pred.var(), var, rtol=1e-10)
    with pytest.raises(gpmsa.GPMSAError, match="extrapolate must be"):
        gpmsa.emulator_prediction(emu, [[0.5]], t, extrapolate=1.0)


def test_full_prediction_names_obs_not_x_obs():
    emu = _emulator()
    lo, hi = emu.domain["v"]
    xo = hi + 0.3 * (hi - lo)
    obs = gpmsa.ObsData(x=[[xo]], y=[[float(np.sin(3 * hi)) + 0.5]])
    post = _quiet(gpmsa.calibrate, emu, obs.x, obs.y, n_samples=20, n_burn=5, seed=0,
                  extrapolate=True)  # fmt: skip
    far = (
        rf"^obs v={xo:.6g} lies outside the emulator's domain .* pass extrapolate=True to allow it$"
    )
    with pytest.raises(gpmsa.GPMSAError, match=far):
        gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, seed=1)
