"""API consistency (session 66): a call refuses what it cannot use as its siblings do, with a
GPMSAError naming the argument and what it got, never an AttributeError from inside."""

import warnings
from functools import cache

import matplotlib
import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError
from gpmsa.predictive import calibrated_predict

matplotlib.use("Agg")


@cache
def _fits():
    """A scalar emulator of (v, GD) and a joint fit of it with five observations (short runs)."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(0.0, 2.0, (16, 1)), rng.uniform(0.0, 1.0, (16, 1))
    data = gpmsa.SimData(x=x, t=t, y=np.sin(x) + t**2, x_names=["v"], t_names=["GD"])
    xo = np.linspace(0.2, 1.8, 5)[:, None]
    obs = gpmsa.ObsData(x=xo, y=np.sin(xo) + 0.25)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short runs: not converged
        emu = gpmsa.fit(data, n_iter=40, tune=False, seed=0)
        joint = gpmsa.fit(data, obs, n_iter=40, tune=False, seed=0)
    return emu, joint, obs


def test_calibrated_predict_refuses_a_non_emulator_as_calibrate_does():
    emu, joint, _ = _fits()
    post = gpmsa.calibration_posterior(joint)
    for bad in (3, None, "jackal.gpmsa", post):
        with pytest.raises(GPMSAError, match="calibration needs a gpmsa.Emulator"):
            gpmsa.calibrate(bad, 1.0, 1.2)
        with pytest.raises(GPMSAError, match=r"emulator lacks \[.*calibrated_predict needs a "
                           r"gpmsa\.Emulator, got " + type(bad).__name__):  # fmt: skip
            calibrated_predict(bad, post, 1.0)


def test_full_prediction_refuses_a_posterior_that_is_none_as_calibrated_predict_does():
    _, joint, obs = _fits()
    for bad in (3, {"GD": np.array([0.5])}):
        with pytest.raises(GPMSAError, match=f"posterior must be a gpmsa.Posterior, got "
                           f"{type(bad).__name__}"):  # fmt: skip
            gpmsa.full_prediction(joint, obs, 1.0, posterior=bad)
        with pytest.raises(GPMSAError, match="posterior must be a gpmsa.Posterior"):
            calibrated_predict(joint, bad, 1.0)


def test_calibration_posterior_names_what_it_got_when_it_is_no_emulator():
    emu, joint, _ = _fits()
    post = gpmsa.calibration_posterior(joint)
    for bad in (3, None, post):
        with pytest.raises(GPMSAError, match="calibration_posterior needs a gpmsa.Emulator of a "
                           f"joint fit, got {type(bad).__name__}"):  # fmt: skip
            gpmsa.calibration_posterior(bad)
    with pytest.raises(GPMSAError, match="no calibration draws: it was fitted without"):
        gpmsa.calibration_posterior(emu)  # an Emulator without them: as before


def test_a_dict_as_x_is_named_a_dict_by_every_prediction():
    emu, joint, obs = _fits()
    calls = (
        lambda x: emu.predict(x, 0.5),
        lambda x: gpmsa.emulator_prediction(emu, x, 0.5, n_draws=2),
        lambda x: gpmsa.full_prediction(joint, obs, x, n_draws=2),
        lambda x: gpmsa.calibrate(emu, x, 1.2, n_samples=20, n_burn=5, tune=False, seed=0),
    )
    for call in calls:
        with pytest.raises(GPMSAError, match=r"must be a numeric array, got dict"):
            call({"v": 1.0})  # it said "got list" in emulator_prediction and full_prediction
        assert call(1.0) is not None  # a number is one point, in all of them


def test_plots_data_refuses_an_unknown_color_by_for_a_scalar_output_too():
    rng = np.random.default_rng(1)
    x, t = rng.uniform(size=(10, 1)), rng.uniform(size=(10, 1))
    sim = gpmsa.SimData(x=x, t=t, y=x + t, x_names=["v"], t_names=["GD"])
    with pytest.raises(GPMSAError, match=r"color_by must be one of the inputs \['v', 'GD'\], "
                       "got 'gd'"):  # fmt: skip
        gpmsa.plots.data(sim, color_by="gd")
    assert len(gpmsa.plots.data(sim, color_by="GD").axes) == 2  # a known name: as before
