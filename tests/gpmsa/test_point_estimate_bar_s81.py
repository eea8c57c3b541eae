"""``progress=True`` at the point estimate (``draws=False``): cross_validate, sensitivity and
emulator_prediction run one vectorised set of parameters there and, as ``Emulator.predict``
and the docs' "Progress bars" say, show no bar; the result is the same to the bit."""

import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa

X_NEW = np.array([[0.2], [0.5], [0.8]])
T_NEW = np.array([[0.3], [0.6], [0.4]])


@cache
def _emulator():
    """20 runs of two outputs, a short chain."""
    rng = np.random.default_rng(5)
    x, t = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1))
    data = gpmsa.SimData(x=x, t=t, y=np.hstack([np.sin(3 * x) + t, x * t]), x_names=["x"],
                         t_names=["t"])  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(data, n_iter=20, tune=False, seed=0)


CALLS = {
    "cross_validate": lambda p: gpmsa.cross_validate(_emulator(), draws=False, progress=p),
    "sensitivity": lambda p: gpmsa.sensitivity(
        _emulator(), draws=False, main_effect_grid=3, progress=p
    ),
    "emulator_prediction": lambda p: gpmsa.emulator_prediction(
        _emulator(), X_NEW, T_NEW, draws=False, n_rlz=2, seed=1, progress=p
    ),
    "predict": lambda p: _emulator().predict(X_NEW, T_NEW, draws=False, progress=p),
}


def _arrays(result):
    if isinstance(result, tuple):
        return list(result)
    return [v for v in vars(result).values() if isinstance(v, np.ndarray)]


@pytest.mark.parametrize("name", list(CALLS))
def test_point_estimate_shows_no_bar_and_changes_no_bit(name, capfd):
    _emulator()
    capfd.readouterr()  # the cached fit's own output out of the way
    shown = CALLS[name](True)
    err = capfd.readouterr().err
    assert err == "", err[-300:]
    quiet = CALLS[name](False)
    a, b = _arrays(quiet), _arrays(shown)
    assert len(a) == len(b) > 0
    for u, v in zip(a, b, strict=True):
        assert u.dtype == v.dtype and np.array_equal(u, v, equal_nan=True)


@pytest.mark.parametrize("name", ["cross_validate", "sensitivity", "emulator_prediction"])
def test_draws_still_show_the_bar(name, capfd):
    """With draws the bar stays: the same calls at draws=True, two draws."""
    emu = _emulator()
    capfd.readouterr()
    if name == "cross_validate":
        gpmsa.cross_validate(emu, n_draws=2, progress=True)
    elif name == "sensitivity":
        gpmsa.sensitivity(emu, n_draws=2, main_effect_grid=3, progress=True)
    else:
        gpmsa.emulator_prediction(emu, X_NEW, T_NEW, n_draws=2, n_rlz=2, seed=1, progress=True)
    assert f"{name}: 100%" in capfd.readouterr().err
