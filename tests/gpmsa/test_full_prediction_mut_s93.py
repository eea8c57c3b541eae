"""Exact checks of full_prediction found by mutation testing (session 93).

A tiny scalar-output emulator at fixed parameters (`four_run_emulator`) and a hand-made
Posterior with a constant discrepancy: the conditional weights are compared with one dense
Gaussian solve, the realizations with a replay of the seeded generator, and the moments with
their formulas.
"""

import dataclasses
import typing

import numpy as np
import pytest
from _predict_cases import four_run_emulator

import gpmsa
from gpmsa import GPMSAError
from gpmsa.model.correlation import correlation as R
from gpmsa.predictive import FullPrediction, full_prediction
from gpmsa.predictive._common import mvn_factor

X_OBS = np.array([[0.2], [0.7]])
Y_OBS = np.array([[2.0], [2.6]])
X_NEW = np.array([[0.4], [0.9]])
SAMPLES = {
    "t": np.array([0.3, 0.6, 0.8]),
    "lamOs": np.array([4.0, 2.0, 8.0]),
    "betaV": np.array([0.5, 1.5, 3.0]),
    "lamVz": np.array([3.0, 1.0, 6.0]),
}


def _case(n_rlz: int = 2, seed: int = 4):
    emu = four_run_emulator()
    obs = gpmsa.ObsData(x=X_OBS, y=Y_OBS)
    post = gpmsa.Posterior({k: v.copy() for k, v in SAMPLES.items()})
    pred = full_prediction(emu, obs, X_NEW, posterior=post, discrepancy="constant",
                           n_rlz=n_rlz, seed=seed)  # fmt: skip
    return emu, pred


def _dense(emu, i: int):
    """Mean and covariance of [v(X_NEW); u(X_NEW)] given w and z, one joint Gaussian solve:
    z = u(X_OBS) + v(X_OBS) + e on the standardised scale (x and t in [0, 1]: unit = native)."""
    prm, std = emu.params, emu.standardizer
    th, lam_os = SAMPLES["t"][i], SAMPLES["lamOs"][i]
    bv, lvz = np.array([SAMPLES["betaV"][i]]), SAMPLES["lamVz"][i]
    bu, luz, lws, lwo = prm["betaU"][:, 0], prm["lamUz"][0], prm["lamWs"][0], prm["lamWOs"][0]
    xto = np.hstack([X_OBS, np.full((2, 1), th)])
    xtn = np.hstack([X_NEW, np.full((2, 1), th)])
    zt, m = emu.zt, emu.zt.shape[0]
    z = (Y_OBS[:, 0] - std.y_mean[0]) / std.y_sd
    s_zz = R(X_OBS, None, bv) / lvz + R(xto, None, bu) / luz + np.eye(2) / lws + np.eye(2) / lam_os
    s_zw = R(xto, zt, bu) / luz
    s_ww = R(zt, None, bu) / luz + (1.0 / (emu.lam_sim[0] * lwo) + 1.0 / lws) * np.eye(m)
    sig = np.block([[s_zz, s_zw], [s_zw.T, s_ww]])
    data = np.concatenate([z, emu.w[:, 0]])
    cross = np.zeros((2 + m, 4))  # columns: v(X_NEW) then u(X_NEW)
    cross[:2, :2] = R(X_OBS, X_NEW, bv) / lvz
    cross[:2, 2:] = R(xto, xtn, bu) / luz
    cross[2:, 2:] = R(zt, xtn, bu) / luz
    prior = np.zeros((4, 4))
    prior[:2, :2] = R(X_NEW, None, bv) / lvz
    prior[2:, 2:] = R(xtn, None, bu) / luz + np.eye(2) / lws
    W = np.linalg.solve(sig, cross)
    return W.T @ data, prior - W.T @ cross


def test_scalar_output_weights_equal_one_dense_gaussian_solve():
    emu, pred = _case()
    assert pred.mu.shape == (3, 2, 2) and pred.cov.shape == (3, 2, 2, 2)
    np.testing.assert_array_equal(pred.draw_index, [0, 1, 2])
    np.testing.assert_allclose(pred.theta[:, 0], SAMPLES["t"], rtol=1e-14)
    np.testing.assert_array_equal(pred.lamOs, SAMPLES["lamOs"])
    for i in range(3):
        mean, cov = _dense(emu, i)
        np.testing.assert_allclose(pred.mu[i], mean.reshape(2, 2).T, rtol=1e-7, atol=1e-9)
        for k in range(2):  # point k's covariance of (v, u)
            np.testing.assert_allclose(pred.cov[i, k], cov[k::2, k::2], rtol=1e-7, atol=1e-9)


def test_realizations_replay_the_seeded_generator():
    """eta, delta and y from the latents and the noise, exactly as the module docstring says."""
    emu, pred = _case(n_rlz=2, seed=4)
    std = emu.standardizer
    rng = np.random.default_rng(4)
    lat = []
    for i in range(3):
        mean, cov = _dense(emu, i)  # comp-major: v at both points, then u
        A = mvn_factor(cov)
        r = mean + rng.standard_normal((2, 4)) @ A.T
        lat.append(r.reshape(2, 2, 2).transpose(0, 2, 1))
    lat = np.concatenate(lat)  # (6, N, [v, u])
    np.testing.assert_allclose(pred.v[..., 0], lat[..., 0], rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(pred.u[..., 0], lat[..., 1], rtol=1e-6, atol=1e-7)
    sd, mean = std.y_sd, std.y_mean[0]
    np.testing.assert_allclose(pred.eta[..., 0], lat[..., 1] * sd + mean, rtol=1e-6)
    np.testing.assert_allclose(pred.delta[..., 0], lat[..., 0] * sd, rtol=1e-6, atol=1e-7)
    noise = rng.standard_normal((6, 2, 1)) / np.sqrt(np.repeat(SAMPLES["lamOs"], 2))[:, None, None]
    np.testing.assert_allclose(pred.y, pred.eta + pred.delta + noise * sd, rtol=1e-12)
    np.testing.assert_allclose(pred.zeta, pred.eta + pred.delta, rtol=0, atol=0)


def test_mean_and_variance_follow_their_formulas():
    """mean: the draws' average conditional mean; var: the law of total variance; y adds the
    noise 1 / lamOs; delta has no y_mean offset (standardised scale times y_sd)."""
    emu, pred = _case()
    sd, y_mean = pred.y_sd, pred.y_mean
    mu, cov = pred.mu, pred.cov  # (S, N, [v, u])
    pieces = {
        "eta": (mu[..., 1], cov[..., 1, 1], y_mean),
        "delta": (mu[..., 0], cov[..., 0, 0], 0.0),
        "zeta": (mu.sum(-1), cov.sum((-1, -2)), y_mean),
        "y": (mu.sum(-1), cov.sum((-1, -2)) + 1.0 / SAMPLES["lamOs"][:, None], y_mean),
    }
    for what, (m, v, offset) in pieces.items():
        np.testing.assert_allclose(pred.mean(what)[:, 0], m.mean(0) * sd + offset, rtol=1e-12)
        var = (v.mean(0) + m.var(0)) * sd**2
        np.testing.assert_allclose(pred.var(what)[:, 0], var, rtol=1e-12)
    assert pred.p_v == 1 and repr(pred) == (
        "FullPrediction(2 points x 1 outputs, 3 draws x 2 realizations, p_u=1, p_v=1)"
    )


def test_the_result_is_frozen_and_its_hints_resolve():
    _, pred = _case()
    with pytest.raises(dataclasses.FrozenInstanceError):
        pred.y = None
    hints = typing.get_type_hints(FullPrediction)
    assert hints["index_names"] == tuple[str, ...] | None
    assert typing.get_type_hints(full_prediction)["experiment"] == int | None
    assert "q" in typing.get_type_hints(FullPrediction.quantile)


def test_bad_what_level_and_betav_draws_are_named():
    _, pred = _case()
    long = "w" * 200
    with pytest.raises(GPMSAError) as err:
        pred.mean(long)
    assert str(err.value).endswith("got " + repr(long)[:80])
    with pytest.raises(GPMSAError, match=r"level must be a number in \(0, 1\), got 1.5"):
        pred.interval("y", 1.5)
    emu = four_run_emulator()
    obs = gpmsa.ObsData(x=X_OBS, y=Y_OBS)
    for name in ("betaV", "lamVz"):
        bad = {k: v.copy() for k, v in SAMPLES.items()}
        bad[name][1] = 0.0
        with pytest.raises(GPMSAError, match=f"the posterior's {name} draws must be > 0"):
            full_prediction(emu, obs, X_NEW, posterior=gpmsa.Posterior(bad),
                            discrepancy="constant")  # fmt: skip


def test_memory_estimate_is_checked_against_the_limit(monkeypatch):
    """3 draws x 2 realizations at 3 points, one output, p_v + p_u = 2: 8 S (n_rlz N (n_c + 4 l)
    + N n_c^2) + 32 (n_c N)^2 = 24 (36 + 12) + 32 * 36 = 2304 bytes."""
    import gpmsa.limits

    emu = four_run_emulator()
    obs = gpmsa.ObsData(x=X_OBS, y=Y_OBS)
    x3 = np.array([[0.1], [0.4], [0.9]])

    def run():
        return full_prediction(emu, obs, x3, posterior=gpmsa.Posterior(dict(SAMPLES)),
                               discrepancy="constant", n_rlz=2, seed=0)  # fmt: skip

    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", 2304)
    assert run().y.shape == (6, 3, 1)
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", 2303)
    with pytest.raises(gpmsa.limits.ResourceLimitError, match=r"full_prediction\(n_rlz=2\) at 3 "):
        run()


BAD = [
    ({"n_rlz": 0}, "n_rlz must be an integer >= 1"),
    ({"n_rlz": 1.5}, "n_rlz must be an integer >= 1"),
    ({"draws": "yes"}, "draws must be True or False"),
]


@pytest.mark.parametrize(("kw", "message"), BAD)
def test_bad_counts_and_flags_are_named(kw, message):
    emu = four_run_emulator()
    obs = gpmsa.ObsData(x=X_OBS, y=Y_OBS)
    with pytest.raises(GPMSAError, match=message):
        full_prediction(emu, obs, X_NEW, posterior=gpmsa.Posterior(dict(SAMPLES)),
                        discrepancy="constant", **kw)  # fmt: skip
