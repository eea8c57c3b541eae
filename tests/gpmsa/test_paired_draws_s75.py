"""Draw-paired calibrated predictions (GPM/SA's gPred 'wpred', SEPIA's predictions from samples):
each theta draw with the emulator parameters drawn with it (session 75)."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.calibration.observations import draw_positions
from gpmsa.errors import GPMSAError
from gpmsa.model.data import evenly_spaced
from gpmsa.predictive import calibrated_predict

PARAMS = ("betaU", "lamUz", "lamWs", "lamWOs")
X_NEW = np.array([[0.3], [0.6], [0.9]])


def _data():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1))
    data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + 2 * t, x_names=["x"], t_names=["t"])
    xo = np.array([[0.2], [0.5], [0.8]])
    yo = np.sin(3 * xo) + 0.8 + 0.05 * rng.standard_normal((3, 1))
    return data, xo, yo


@pytest.fixture(scope="module")
def joint():
    data, xo, yo = _data()
    emu = gpmsa.fit(data, gpmsa.ObsData(x=xo, y=yo), n_iter=300, tune=False, seed=0)
    return data, emu, xo, yo


def _by_hand(data, emu, theta, pos, resid=True):
    """Per component k: the single-draw predictive (an emulator built at draw pos[k]'s
    parameters, ``Emulator.predict`` at its point estimate) at (X_NEW, theta[k])."""
    ms, vs = [], []
    for th, d in zip(theta, pos, strict=True):
        one = gpmsa.Emulator.from_params(data, {k: emu.draws[k][d] for k in PARAMS})
        m, v = one.predict(X_NEW, np.full((len(X_NEW), 1), th), resid=resid)
        ms.append(m)
        vs.append(v)
    return np.array(ms), np.array(vs)


def test_joint_fit_pairs_each_theta_with_its_own_draw(joint):
    data, emu, _, _ = joint
    post = gpmsa.calibration_posterior(emu)
    pred = calibrated_predict(emu, post, X_NEW, draws=True, n_theta=12)
    idx = evenly_spaced(emu.n_draws, 12)
    ms, vs = _by_hand(data, emu, post.samples["t"][idx], idx)
    assert np.allclose(pred.mean, ms.mean(axis=0), rtol=0, atol=1e-10)
    between = ms.var(axis=0)
    assert np.allclose(pred.var, vs.mean(axis=0) + between, rtol=1e-10, atol=0)
    assert np.allclose(pred.comp_mean, ms, rtol=0, atol=1e-10)
    point = calibrated_predict(emu, post, X_NEW, n_theta=12)
    # the same theta draws at the point estimate: narrower where the emulator is uncertain
    assert np.all(pred.var > point.var)
    assert np.all(between > 0)


def test_default_is_the_point_estimate_bit_for_bit(joint):
    _, emu, _, _ = joint
    post = gpmsa.calibration_posterior(emu)
    default = calibrated_predict(emu, post, X_NEW, n_theta=12)
    explicit = calibrated_predict(emu, post, X_NEW, n_theta=12, draws=False)
    idx = evenly_spaced(emu.n_draws, 12)
    theta = post.samples["t"][idx]
    m, v = emu.predict(np.tile(X_NEW, (12, 1)), np.repeat(theta, len(X_NEW))[:, None])
    for a in (default, explicit):
        assert np.array_equal(a.comp_mean, m.reshape(12, len(X_NEW), 1))
        assert np.array_equal(a.comp_var, v.reshape(12, len(X_NEW), 1))
    assert np.array_equal(default.mean, explicit.mean) and np.array_equal(default.var, explicit.var)


def test_calibrate_with_emulator_draws_records_and_pairs_them(joint):
    data, emu, xo, yo = joint
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        post = gpmsa.calibrate(emu, xo, yo, n_samples=300, n_burn=100, seed=1, n_chains=2,
                               emulator_params="draws", n_emulator_draws=4)  # fmt: skip
    rec = post.info["emulator_draws"]
    assert rec.shape == post.samples["t"].shape == (400,)
    assert set(np.unique(rec)) <= set(draw_positions(emu, 4))
    assert np.unique(rec).size > 1
    pred = calibrated_predict(emu, post, X_NEW, draws=True, n_theta=10, noise=True)
    idx = evenly_spaced(400, 10)
    ms, vs = _by_hand(data, emu, post.samples["t"][idx], rec[idx])
    vs = vs + emu.standardizer.var_from_std(1.0 / post.samples["lamOs"][idx])[:, None, None]
    assert np.allclose(pred.mean, ms.mean(axis=0), rtol=0, atol=1e-10)
    assert np.allclose(pred.var, vs.mean(axis=0) + ms.var(axis=0), rtol=1e-10, atol=0)


def test_sources_without_paired_draws_are_refused(joint):
    data, emu, xo, yo = joint
    point = gpmsa.calibrate(emu, xo, yo, n_samples=200, n_burn=50, seed=1)
    assert "emulator_draws" not in point.info
    with pytest.raises(GPMSAError, match="records none.*not this emulator's joint-fit draws"):
        calibrated_predict(emu, point, X_NEW, draws=True)
    alone = gpmsa.fit(data, n_iter=60, tune=False, seed=0)
    post = gpmsa.calibrate(alone, xo, yo, n_samples=200, n_burn=50, seed=1)
    with pytest.raises(GPMSAError, match="fitted without observations"):
        calibrated_predict(alone, post, X_NEW, draws=True)
    bare = gpmsa.Emulator.from_params(data, emu.params)
    with pytest.raises(GPMSAError, match="kept none"):
        calibrated_predict(bare, gpmsa.Posterior(dict(point.samples)), X_NEW, draws=True)
    bad = gpmsa.Posterior(dict(point.samples), info={"emulator_draws": [0, 1]})
    with pytest.raises(GPMSAError, match=r"info\['emulator_draws'\] must hold one position"):
        calibrated_predict(emu, bad, X_NEW, draws=True)
    with pytest.raises(GPMSAError, match="draws"):
        calibrated_predict(emu, point, X_NEW, draws="yes")


def test_full_prediction_draws_option(joint):
    data, emu, xo, yo = joint
    obs = gpmsa.ObsData(x=xo, y=yo)
    post = gpmsa.calibration_posterior(emu)
    own = gpmsa.full_prediction(emu, obs, X_NEW, n_draws=8, seed=3)
    assert np.array_equal(
        own.mu, gpmsa.full_prediction(emu, obs, X_NEW, n_draws=8, seed=3, draws=True).mu
    )
    paired = gpmsa.full_prediction(emu, obs, X_NEW, posterior=post, n_draws=8, seed=3, draws=True)
    assert np.allclose(paired.mu, own.mu, rtol=0, atol=1e-10)
    assert np.allclose(paired.cov, own.cov, rtol=0, atol=1e-10)
    at_point = gpmsa.full_prediction(emu, obs, X_NEW, posterior=post, n_draws=8, seed=3)
    explicit = gpmsa.full_prediction(emu, obs, X_NEW, posterior=post, n_draws=8, seed=3,
                                     draws=False)  # fmt: skip
    assert np.array_equal(at_point.mu, explicit.mu) and np.array_equal(at_point.y, explicit.y)
    assert not np.allclose(at_point.mu, own.mu, rtol=0, atol=1e-10)
    own_point = gpmsa.full_prediction(emu, obs, X_NEW, n_draws=8, seed=3, draws=False)
    assert np.allclose(own_point.mu, at_point.mu, rtol=0, atol=1e-10)
    point = gpmsa.calibrate(emu, xo, yo, n_samples=200, n_burn=50, seed=1)
    with pytest.raises(GPMSAError, match="full_prediction with draws=True"):
        gpmsa.full_prediction(emu, obs, X_NEW, posterior=point, draws=True)
