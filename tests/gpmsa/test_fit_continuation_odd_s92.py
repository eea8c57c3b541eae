"""Session 92: a fit's continuation (``gpmsa.fitting.continuation``), the odd half of its
mutation sites (session 90 did the even half), pinned where the tests were loose: the values a
message shows of this fit's output scale, and the categorical theta a continuation starts from."""

from __future__ import annotations

import warnings
from types import SimpleNamespace

import numpy as np
from _emulator_edit import replaced

import gpmsa
from gpmsa.fitting import continuation as cont
from gpmsa.model.problem import prepare


def _std(y_mean, given=()):
    return SimpleNamespace(y_mean=np.asarray(y_mean), y_sd=1.0, y_given=tuple(given))


def test_given_shows_three_values_of_this_fits_as_of_the_sources():
    three, four = _std([1.0, 2.0, 3.0]), _std([1.0, 2.0, 3.0, 4.0], ["y_mean"])
    assert cont._given(three, four, "y_mean") == (
        "[1, 2, 3] (the runs' own)",
        "[1, 2, 3, ...] (given)",
    )
    # the fourth value is not shown, so it does not lengthen the shown ones' digits either
    near = _std([1.0, 2.0, 3.0, 3.0 + 1e-9])
    assert cont._given(three, near, "y_mean")[1] == "[1, 2, 3, ...] (the runs' own)"


def test_continued_starts_put_a_float32_rounded_categorical_theta_back_on_its_level():
    rng = np.random.default_rng(3)
    x = rng.random((12, 1))
    t = np.column_stack([rng.random(12), np.arange(12) % 4])  # levels 0, 1/3, 2/3, 1
    sim = gpmsa.SimData(x, t, np.sin(3 * x) + t[:, :1] + 0.5 * t[:, 1:], x_names=["s"],
                        t_names=["k", "kind"], t_categorical=["kind"])  # fmt: skip
    obs = gpmsa.ObsData(x=[[0.2], [0.7]], y=[[0.9], [1.4]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        emu = gpmsa.fit(sim, obs, n_iter=2, n_chains=2, seed=0, tune=False, n_jobs=1)
    theta = np.array(emu.calibration["theta"], dtype=np.float64)  # 2 chains x 2 draws
    theta[:, 0] = np.float32(theta[:, 0])
    theta[:, 1] = np.float32([0.0, 2 / 3, 1.0, 1 / 3])  # as a float32 fit holds the levels
    assert theta[1, 1] != 2 / 3 and theta[3, 1] != 1 / 3
    rounded = replaced(emu, calibration={**emu.calibration, "theta": theta})
    prep = prepare(sim, obs)
    got = cont.continued_starts(rounded, prep.problem, prep.K, obs, 2)["theta"]
    assert got[:, 1].tolist() == [2 / 3, 1 / 3]  # each chain's last draw, on its level
    assert got[:, 0].tolist() == theta[[1, 3], 0].tolist()  # a continuous input as it was
