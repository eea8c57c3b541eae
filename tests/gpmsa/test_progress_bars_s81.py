"""``progress=`` on the looping calls after a fit (cross_validate, sensitivity,
emulator_prediction, full_prediction, calibrated_predict, Emulator.predict / predict_mean with
draws, a Calibrator's grid over emulator draws): a tqdm bar on stderr named for the call, none
without it, and the result bit for bit the same either way."""

import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError

X_NEW = np.array([[0.2], [0.5], [0.8]])
T_NEW = np.array([[0.3], [0.6], [0.4]])


def _quiet_fit(*args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(*args, n_iter=40, tune=False, seed=0, **kw)


@cache
def _emulator():
    """30 runs of two outputs, 30 retained draws."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
    y = np.hstack([np.sin(3 * x) + t, x * t])
    data = gpmsa.SimData(x=x, t=t, y=y, x_names=["x"], t_names=["t"])
    return _quiet_fit(data)


@cache
def _joint():
    """A joint fit with a constant discrepancy, and its observations."""
    rng = np.random.default_rng(1)
    x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
    data = gpmsa.SimData(x=x, t=t, y=x + t, x_names=["x"], t_names=["t"])
    obs = gpmsa.ObsData(x=[[0.2], [0.5], [0.8]], y=[[0.7], [1.1], [1.3]])
    return _quiet_fit(data, obs, discrepancy="constant"), obs


def _arrays(result):
    """The result's arrays, in a fixed order (a dataclass's fields, a tuple's items)."""
    if isinstance(result, np.ndarray):
        return [result]
    if isinstance(result, tuple):
        return [a for r in result for a in _arrays(r)]
    fields = getattr(result, "__dataclass_fields__", None) or vars(result)
    return [np.asarray(getattr(result, k)) for k in fields
            if isinstance(getattr(result, k), np.ndarray)]  # fmt: skip


def _cross_validate(progress):
    return gpmsa.cross_validate(_emulator(), folds=3, seed=0, progress=progress)


def _sensitivity(progress):
    return gpmsa.sensitivity(_emulator(), n_draws=4, pairs="all", main_effect_grid=3,
                             progress=progress)  # fmt: skip


def _emulator_prediction(progress):
    return gpmsa.emulator_prediction(_emulator(), X_NEW, T_NEW, n_rlz=2, joint=True, seed=3,
                                     progress=progress)  # fmt: skip


def _full_prediction(progress):
    emu, obs = _joint()
    return gpmsa.full_prediction(emu, obs, X_NEW, n_rlz=2, seed=4, progress=progress)


def _calibrated_predict(progress):
    emu, _ = _joint()
    post = gpmsa.calibration_posterior(emu)
    return gpmsa.calibrated_predict(emu, post, X_NEW, draws=True, n_theta=10, progress=progress)


def _predict(progress):
    return _emulator().predict(X_NEW, T_NEW, draws=True, progress=progress)


def _predict_mean(progress):
    return _emulator().predict_mean(X_NEW, T_NEW, draws=True, n_draws=7, progress=progress)


def _calibrator(progress):
    emu = _emulator()
    cal = gpmsa.Calibrator(emu, emulator_params="draws", n_emulator_draws=3, n_grid=33, seed=0,
                           progress=progress)  # fmt: skip
    post = cal.update([[0.3], [0.7]], emu.predict_mean([[0.3], [0.7]], [[0.5], [0.5]]))
    return post.grids["t"].density, post.samples["t"], post.samples["lamOs"]


CALLS = {
    "cross_validate": _cross_validate,
    "sensitivity": _sensitivity,
    "emulator_prediction": _emulator_prediction,
    "full_prediction": _full_prediction,
    "calibrated_predict": _calibrated_predict,
    "predict": _predict,
    "predict_mean": _predict_mean,
    "Calibrator": _calibrator,
}


@pytest.mark.parametrize("name", list(CALLS))
def test_progress_shows_a_named_bar_and_changes_no_bit(name, capsys):
    call = CALLS[name]
    call(False)  # the cached fits' own output out of the way
    capsys.readouterr()
    quiet = call(False)
    assert capsys.readouterr().err == ""
    shown = call(True)
    err = capsys.readouterr().err
    assert f"{name}: 100%" in err, err[-300:]
    a, b = _arrays(quiet), _arrays(shown)
    assert len(a) == len(b) > 0
    for u, v in zip(a, b, strict=True):
        assert u.dtype == v.dtype and np.array_equal(u, v, equal_nan=True)


def test_the_point_estimate_has_no_loop_and_shows_no_bar(capsys):
    emu = _emulator()
    capsys.readouterr()
    mean, var = emu.predict(X_NEW, T_NEW, progress=True)
    assert capsys.readouterr().err == ""
    ref = emu.predict(X_NEW, T_NEW)
    assert np.array_equal(mean, ref[0]) and np.array_equal(var, ref[1])


@pytest.mark.parametrize("name", list(CALLS))
def test_progress_must_be_a_flag(name):
    with pytest.raises(GPMSAError, match=r"progress must be True or False, got 'yes'"):
        CALLS[name]("yes")
