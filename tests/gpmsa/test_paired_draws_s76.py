"""Draw-paired predictions from a grid Calibrator averaging over the emulator's draws, and the
refusals of posteriors that hold no emulator draw to pair (session 76)."""

import pickle
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
XO = np.array([[0.2], [0.5], [0.8]])


@pytest.fixture(scope="module")
def joint():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1))
    data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + 2 * t, x_names=["x"], t_names=["t"])
    yo = np.sin(3 * XO) + 0.8 + 0.05 * rng.standard_normal((3, 1))
    emu = gpmsa.fit(data, gpmsa.ObsData(x=XO, y=yo), n_iter=300, tune=False, seed=0)
    return data, emu, yo


def _by_hand(data, emu, theta, pos, lam):
    """The paired mixture's moments at X_NEW with the observation noise: per component an
    emulator built at draw pos[k]'s parameters, ``Emulator.predict`` at (X_NEW, theta[k]), plus
    1/lamOs[k]."""
    ms, vs = [], []
    for th, d, la in zip(theta, pos, lam, strict=True):
        one = gpmsa.Emulator.from_params(data, {k: emu.draws[k][d] for k in PARAMS})
        m, v = one.predict(X_NEW, np.tile(th, (len(X_NEW), 1)))
        ms.append(m)
        vs.append(v + emu.standardizer.var_from_std(1.0 / la))
    ms, vs = np.array(ms), np.array(vs)
    return ms.mean(axis=0), vs.mean(axis=0) + ms.var(axis=0)


def test_grid_calibrator_records_each_draws_emulator_draw(joint):
    data, emu, yo = joint
    cal = gpmsa.Calibrator(emu, emulator_params="draws", n_emulator_draws=4, n_draws=4000, seed=1)
    post = cal.update(XO, yo)
    pred = calibrated_predict(emu, post, X_NEW, draws=True, n_theta=10, noise=True)
    rec = post.info["emulator_draws"]
    assert rec.shape == post.samples["t"].shape == (4000,)
    assert set(np.unique(rec)) <= set(draw_positions(emu, 4))
    assert np.unique(rec).size > 1
    idx = evenly_spaced(4000, 10)
    mean, var = _by_hand(data, emu, post.samples["t"][idx, None], rec[idx],
                         post.samples["lamOs"][idx])  # fmt: skip
    assert np.allclose(pred.mean, mean, rtol=0, atol=1e-10)
    assert np.allclose(pred.var, var, rtol=1e-10, atol=0)
    # the draws' sets are the mixture's: set j's share is its posterior mass, the likelihood
    # of each draw on the fixed grid (a point Calibrator at that draw) times the theta prior
    # (here 0.33, 0.23, 0.20, 0.24: an even share, 0.25 each, is 11 sd off the first)
    mass = []
    for d in draw_positions(emu, 4):
        one = gpmsa.Emulator.from_params(data, {k: emu.draws[k][d] for k in PARAMS})
        nodes, ll = gpmsa.Calibrator(one).log_likelihood_grid(XO, yo)
        mass.append(np.exp(ll + cal._log_prior_theta))
    share = np.array(mass).sum(axis=1) / np.sum(mass)
    seen = np.array([np.mean(rec == d) for d in draw_positions(emu, 4)])
    assert np.all(np.abs(seen - share) < 4 * np.sqrt(share * (1 - share) / 4000) + 1e-3)


def test_recorded_once_drawn_and_kept_through_pickle(joint):
    _, emu, yo = joint
    cal = gpmsa.Calibrator(emu, emulator_params="draws", n_emulator_draws=3, n_draws=200, seed=2)
    post = cal.update(XO, yo)
    back = pickle.loads(pickle.dumps(post))  # the lazy draws are made for pickling
    assert np.array_equal(back.info["emulator_draws"], post.info["emulator_draws"])
    again = cal.update(XO, yo, seed=5)
    fresh = cal.update(XO, yo, seed=5)
    assert np.array_equal(again.samples["t"], fresh.samples["t"])
    assert np.array_equal(again.info["emulator_draws"], fresh.info["emulator_draws"])


def test_two_parameter_and_categorical_grids_record_them():
    rng = np.random.default_rng(1)
    x, t = rng.uniform(size=(24, 1)), rng.uniform(size=(24, 2))
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t[:, :1] - t[:, 1:], t_names=["a", "b"])
    emu = gpmsa.fit(sim, n_iter=100, tune=False, seed=0)
    yo = np.sin(3 * XO) + 0.3
    post = gpmsa.Calibrator(emu, emulator_params="draws", n_emulator_draws=3, n_draws=300,
                            seed=1).update(XO, yo)  # fmt: skip
    assert "emulator_draws" not in post.info  # recorded as the draws are made (lazily)
    _ = post.samples
    assert np.unique(post.info["emulator_draws"]).size > 1
    pred = calibrated_predict(emu, post, X_NEW, draws=True, n_theta=6)
    idx = evenly_spaced(300, 6)
    pos = post.info["emulator_draws"][idx]
    theta = np.column_stack([post.samples["a"][idx], post.samples["b"][idx]])
    ms = [gpmsa.Emulator.from_params(sim, {k: emu.draws[k][d] for k in PARAMS}).predict(
        X_NEW, np.tile(th, (3, 1)))[0] for th, d in zip(theta, pos, strict=True)]  # fmt: skip
    assert np.allclose(pred.mean, np.mean(ms, axis=0), rtol=0, atol=1e-10)
    levels = np.column_stack([rng.integers(0, 3, 24), t[:, 1]])
    cat = gpmsa.SimData(x=x, t=levels, y=np.sin(3 * x) + levels[:, :1] - t[:, 1:],
                        t_names=["c", "b"], t_categorical=["c"])  # fmt: skip
    emu = gpmsa.fit(cat, n_iter=100, tune=False, seed=0)
    cal = gpmsa.Calibrator(emu, emulator_params="draws", n_emulator_draws=3, n_draws=300, seed=1)
    post = cal.update(XO, yo + 1.0)
    _ = post.samples
    rec = post.info["emulator_draws"]
    assert rec.shape == (300,) and set(np.unique(rec)) <= set(draw_positions(emu, 3))


def test_point_estimate_and_calibrate_study_refusals_say_why(joint):
    data, emu, yo = joint
    post = gpmsa.Calibrator(emu, n_draws=200, seed=1).update(XO, yo)
    _ = post.samples
    assert "emulator_draws" not in post.info
    with pytest.raises(GPMSAError, match=r"point estimate \(emulator_params='point'\).*"
                       r"Calibrator\(emu, emulator_params='draws'\)"):  # fmt: skip
        calibrated_predict(emu, post, X_NEW, draws=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        study = gpmsa.calibrate_study([emu, emu], [XO, XO], [yo, yo], shared=["t"],
                                      n_samples=150, n_burn=50, seed=1)  # fmt: skip
    with pytest.raises(GPMSAError, match="calibrate_study calibrates at each model's point "
                       "estimate.*fit_study"):  # fmt: skip
        calibrated_predict(emu, study.member_posterior(0), X_NEW, draws=True)
    with pytest.raises(GPMSAError, match="calibrate_study"):
        gpmsa.full_prediction(emu, gpmsa.ObsData(x=XO, y=yo), X_NEW,
                              posterior=study.member_posterior(1), draws=True)  # fmt: skip
    hand = gpmsa.Posterior(dict(post.samples))  # no record of how it was made: no reason given
    with pytest.raises(GPMSAError, match=r"records none \(info\['emulator_draws'\]\); and"):
        calibrated_predict(emu, hand, X_NEW, draws=True)


def test_mcmc_calibrator_records_them_as_calibrate(joint):
    _, emu, yo = joint
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        cal = gpmsa.Calibrator(emu, method="mcmc", emulator_params="draws", n_emulator_draws=3,
                               mcmc_options={"n_samples": 200, "n_burn": 50}, seed=1)  # fmt: skip
        post = cal.update(XO, yo)
    assert post.info["emulator_draws"].shape == (150,)
    assert calibrated_predict(emu, post, X_NEW, draws=True, n_theta=5).mean.shape == (3, 1)
