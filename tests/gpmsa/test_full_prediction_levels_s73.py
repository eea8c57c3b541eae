"""``full_prediction``'s theta of a categorical calibration parameter is exactly its level codes
(session 73 review: with 24 levels the unit scale's round trip gave 12.999999999999998 for the
posterior's 13, so ``pred.theta == 13`` selected no draw; the posterior's samples, a joint fit's
``theta_native`` and ``calibrate``'s draws hold 13.0)."""

from __future__ import annotations

import warnings

import numpy as np

import gpmsa


def test_full_prediction_theta_is_the_level_code():
    rng = np.random.default_rng(0)
    m = 48
    x = rng.random((m, 1))
    kind = np.arange(m) % 24
    sim = gpmsa.SimData(x, kind[:, None], (np.sin(3 * x[:, 0]) + 0.05 * kind)[:, None],
                        x_names=["s"], t_names=["kind"], t_categorical=["kind"])  # fmt: skip
    prm = {"betaU": [[2.0], [1.0]], "lamUz": [1.0], "lamWs": [1e5], "lamWOs": [1e5]}
    emu = gpmsa.Emulator.from_params(sim, prm)
    xo = np.linspace(0.1, 0.9, 5)[:, None]
    obs = gpmsa.ObsData(x=xo, y=(np.sin(3 * xo[:, 0]) + 0.05 * 13)[:, None])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = gpmsa.calibrate(emu, x_obs=xo, y_obs=obs.y, n_samples=40, n_burn=5, seed=0)
        pred = gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, seed=1)
    assert 13.0 in post.samples["kind"]
    drawn = post.samples["kind"][pred.draw_index]
    np.testing.assert_array_equal(pred.theta[:, 0], drawn)  # 12.999999999999998 before
    assert set(np.unique(pred.theta).tolist()) <= set(range(24))
