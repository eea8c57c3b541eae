"""Calibration priors chosen online (``Emulator.with_calibration_priors``): a shared emulator's
file fixes theta's, lamOs's and lamVz's priors at fit time; a calibration can now use others."""

import functools
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa import GammaPrior

NOISE_SD = 0.05


@functools.cache
def _case():
    rng = np.random.default_rng(2)
    x, t = rng.random((30, 1)), rng.random((30, 1))
    data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t, x_names=["x"], t_names=["t"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(data, n_iter=800, seed=0)
    xo = np.linspace(0.1, 0.9, 4)[:, None]
    yo = np.sin(3 * xo) + 0.6 + NOISE_SD * rng.standard_normal(xo.shape)
    return emu, xo, yo


def test_a_known_noise_level_holds_lamOs():
    emu, xo, yo = _case()
    y_sd = emu.standardizer.y_sd
    a = 400.0  # relative sd 5%
    known = emu.with_calibration_priors(lamOs=GammaPrior(a, a * (NOISE_SD / y_sd) ** 2))
    post = gpmsa.calibrate(known, xo, yo, n_samples=3000, n_burn=500, seed=1)
    vague = gpmsa.calibrate(emu, xo, yo, n_samples=3000, n_burn=500, seed=1)
    target = (y_sd / NOISE_SD) ** 2
    assert np.median(post.samples["lamOs"]) == pytest.approx(target, rel=0.15)
    assert np.std(np.log(post.samples["lamOs"])) < 0.5 * np.std(np.log(vague.samples["lamOs"]))


def test_a_theta_prior_moves_the_grid_and_the_mcmc_alike():
    emu, xo, yo = _case()
    firm = emu.with_calibration_priors(theta_mean=0.2, theta_sd=0.02)
    grid = gpmsa.Calibrator(firm).update(xo, yo)
    mcmc = gpmsa.calibrate(firm, xo, yo, n_samples=4000, n_burn=500, seed=2)
    free = gpmsa.Calibrator(emu).update(xo, yo)
    t_min, t_max = emu.domain["t"]
    prior_native = t_min + 0.2 * (t_max - t_min)
    assert abs(grid.mean("t") - prior_native) < abs(free.mean("t") - prior_native)
    assert mcmc.mean("t") == pytest.approx(grid.mean("t"), abs=0.15 * grid.sd("t") + 1e-3)


def test_the_copy_is_another_emulator_saved_with_its_priors(tmp_path):
    emu, xo, yo = _case()
    other = emu.with_calibration_priors(lamOs=GammaPrior(2.0, 1e-2))
    assert other.model_sha256 != emu.model_sha256
    assert other.priors.lamOs == GammaPrior(2.0, 1e-2) and other.priors.lamWOs == emu.priors.lamWOs
    np.testing.assert_array_equal(other.w, emu.w)
    back = gpmsa.load(other.save(tmp_path / "e.gpmsa"))
    assert back.model_sha256 == other.model_sha256
    post = gpmsa.calibrate(other, xo, yo, n_samples=200, n_burn=50, seed=0)
    with pytest.raises(gpmsa.GPMSAError, match="another emulator|emulator_sha256|other emulator"):
        gpmsa.predictive.calibrated_predict(emu, post, [[0.5]])
    gpmsa.predictive.calibrated_predict(back, post, [[0.5]])


@pytest.mark.parametrize(
    ("kw", "match"),
    [({"lamOs": 3.0}, "must be a gpmsa.GammaPrior"), ({"theta_sd": -1.0}, "theta_sd")],
)
def test_bad_priors_are_refused(kw, match):
    emu, _, _ = _case()
    with pytest.raises(gpmsa.GPMSAError, match=match):
        emu.with_calibration_priors(**kw)


def test_a_joint_fits_copy_drops_the_draws_made_under_the_old_priors():
    """It predicted from the old theta draws without posterior= (walkthrough)."""
    rng = np.random.default_rng(4)
    x, t = rng.random((20, 1)), rng.random((20, 1))
    data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t, x_names=["x"], t_names=["t"])
    obs = gpmsa.ObsData(x=[[0.2], [0.7]], y=[[np.sin(0.6) + 0.6], [np.sin(2.1) + 0.6]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        joint = gpmsa.fit(data, obs, n_iter=60, seed=0, tune=False)
    copy = joint.with_calibration_priors(theta_mean=0.2, theta_sd=0.01)
    assert joint.calibration and not copy.calibration
    with pytest.raises(gpmsa.GPMSAError, match="calibration draws"):
        gpmsa.full_prediction(copy, obs, [[0.5]])
    assert joint.with_calibration_priors().calibration  # nothing changed: kept
