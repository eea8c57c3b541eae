"""A calibration Posterior records the emulator it was drawn with (info "emulator_sha256",
``Emulator.model_sha256``), and the predictions that take an emulator and a posterior refuse
another emulator's (before: taken whenever the parameter names matched, mixing emulator b's
predictive with draws made under emulator a)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import gpmsa
from gpmsa.predictive import calibrated_predict

sys.path.insert(0, str(Path(__file__).parent))
from _study_cases import EXACT, emulator, observations, sim_data  # noqa: E402

REFUSED = r"posterior= was drawn with another emulator \(.*model_sha256 [0-9a-f]{12}\.\.\."


@pytest.fixture(scope="module")
def case():
    """emu_a and emu_b (the same runs, another nugget), observations and emu_a's posterior."""
    emu_a, emu_b = emulator(), emulator(lam_w=EXACT)
    x, y = observations(0.6, 6, 0.02, np.random.default_rng(0))
    post_a = gpmsa.calibrate(emu_a, x, y, n_samples=300, n_burn=50, seed=1, tune=False)
    return emu_a, emu_b, x, y, post_a


def test_the_fingerprint_is_the_content_not_the_metadata(tmp_path):
    emu = emulator()
    assert len(emu.model_sha256) == 64 and emu.model_sha256 is emu.model_sha256  # cached
    loaded = gpmsa.load(emu.save(tmp_path / "a.gpmsa"))
    assert loaded.model_sha256 == emu.model_sha256
    params = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1000.0], "lamWOs": [1000.0]}
    noted = gpmsa.Emulator.from_params(sim_data(), params, metadata={"note": "another"})
    assert noted.model_sha256 == emu.model_sha256  # metadata is not content
    assert emulator(lam_w=EXACT).model_sha256 != emu.model_sha256  # other parameters
    assert emulator(t_hi=2.0).model_sha256 != emu.model_sha256  # other runs
    assert emulator(t_name="s").model_sha256 != emu.model_sha256  # other names


def test_calibrated_predict_refuses_another_emulators_posterior(case, tmp_path):
    emu_a, emu_b, _, _, post_a = case
    assert post_a.info["emulator_sha256"] == emu_a.model_sha256
    with pytest.raises(gpmsa.GPMSAError, match=REFUSED):
        calibrated_predict(emu_b, post_a, [[0.5]])
    own = calibrated_predict(emu_a, post_a, [[0.5]])
    loaded = gpmsa.load(emu_a.save(tmp_path / "a.gpmsa"))
    again = calibrated_predict(loaded, post_a, [[0.5]])
    np.testing.assert_array_equal(again.mean, own.mean)
    np.testing.assert_array_equal(again.var, own.var)


def test_full_prediction_refuses_another_emulators_posterior(case, tmp_path):
    emu_a, emu_b, x, y, post_a = case
    obs = gpmsa.ObsData(x=x, y=y)
    kw = {"posterior": post_a, "discrepancy": None, "n_draws": 5, "seed": 0}
    with pytest.raises(gpmsa.GPMSAError, match=REFUSED):
        gpmsa.full_prediction(emu_b, obs, [[0.5]], **kw)
    own = gpmsa.full_prediction(emu_a, obs, [[0.5]], **kw)
    loaded = gpmsa.load(emu_a.save(tmp_path / "a.gpmsa"))
    np.testing.assert_array_equal(gpmsa.full_prediction(loaded, obs, [[0.5]], **kw).y, own.y)


def test_every_calibration_path_records_its_emulator(case):
    emu_a, emu_b, x, y, _ = case
    grid = gpmsa.Calibrator(emu_a).update(x, y)
    short = {"n_samples": 60, "n_burn": 10, "tune": False}
    mcmc = gpmsa.Calibrator(emu_a, method="mcmc", mcmc_options=short).update(x, y)
    backend = gpmsa.calibrate(emu_a, x, y, fast=False, n_samples=40, n_burn=10, tune=False, seed=0)
    for post in (grid, mcmc, backend):
        assert post.info["emulator_sha256"] == emu_a.model_sha256
        with pytest.raises(gpmsa.GPMSAError, match=REFUSED):
            calibrated_predict(emu_b, post, [[0.5]])
        calibrated_predict(emu_a, post, [[0.5]])


def test_a_hand_made_posterior_is_taken_as_before(case):
    emu_a, emu_b, _, _, post_a = case
    plain = gpmsa.Posterior({k: post_a.samples[k] for k in ("t", "lamOs")})
    calibrated_predict(emu_b, plain, [[0.5]])  # no record: nothing to compare


def test_a_joint_fits_posterior_refuses_another_emulator():
    rng = np.random.default_rng(0)
    xs, ts = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
    data = gpmsa.SimData(x=xs, t=ts, y=xs + ts, x_names=["x"], t_names=["t"])
    obs = gpmsa.ObsData(x=[[0.2], [0.8]], y=[[0.5], [1.1]])
    emu = gpmsa.fit(data, obs, n_iter=50, tune=False, seed=0)
    other = gpmsa.fit(data, obs, n_iter=50, tune=False, seed=1)
    post = gpmsa.calibration_posterior(emu)
    assert post.info["emulator_sha256"] == emu.model_sha256 != other.model_sha256
    kw = {"posterior": post, "discrepancy": None, "n_draws": 3, "seed": 0}
    gpmsa.full_prediction(emu, obs, [[0.5]], **kw)
    with pytest.raises(gpmsa.GPMSAError, match=REFUSED):
        gpmsa.full_prediction(other, obs, [[0.5]], **kw)


def test_a_study_members_posterior_goes_with_its_own_member(tmp_path):
    emu_a, emu_b = emulator(), emulator(lam_w=EXACT)
    rng = np.random.default_rng(3)
    (x1, y1), (x2, y2) = observations(0.4, 4, 0.03, rng), observations(0.4, 4, 0.03, rng)
    study = gpmsa.calibrate_study([emu_a, emu_b], [x1, x2], [y1, y2], labels=["a", "b"],
                                  shared=["t"], n_samples=120, n_burn=20, seed=2,
                                  tune=False)  # fmt: skip
    post = study.member_posterior("a")
    assert post.info["emulator_sha256"] == emu_a.model_sha256
    calibrated_predict(study.members[0], post, [[0.5]])
    with pytest.raises(gpmsa.GPMSAError, match=REFUSED.replace(r"\(", r"\(study model 'a'\) \(")):
        calibrated_predict(study.members[1], post, [[0.5]])
    study.save(tmp_path / "s.gpmsa")
    loaded = gpmsa.load_study(tmp_path / "s.gpmsa")
    back = loaded.member_posterior("b")
    assert back.info["emulator_sha256"] == emu_b.model_sha256
    obs_b = gpmsa.ObsData(x=x2, y=y2)
    kw = {"posterior": back, "discrepancy": None, "n_draws": 3, "seed": 0}
    gpmsa.full_prediction(loaded.members[1], obs_b, [[0.5]], **kw)
    gpmsa.full_prediction(emu_b, obs_b, [[0.5]], **kw)  # the member before saving: the same
    with pytest.raises(gpmsa.GPMSAError, match=REFUSED):
        gpmsa.full_prediction(loaded.members[0], obs_b, [[0.5]], **kw)
