"""A categorical calibration parameter's quantiles from draws (``gpmsa.calibrate``) are levels,
as on the Calibrator's grid (session 73: ``np.quantile`` had interpolated between levels)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from _level_cases import level_case

import gpmsa


def test_a_draws_quantile_of_a_recorded_level_parameter_is_a_level():
    draws = {"kind": np.array([0.0, 0.0, 1.0, 1.0]), "k": np.array([0.1, 0.2, 0.3, 0.4])}
    post = gpmsa.Posterior(draws, info={"levels": {"kind": [0.0, 1.0, 2.0]}})
    assert post.quantile("kind", 0.5) == 0.0  # linear interpolation gave 0.5
    np.testing.assert_array_equal(post.quantile("kind", [0.25, 0.51, 1.0]), [0.0, 1.0, 1.0])
    assert post.interval("kind", 0.5) == (0.0, 1.0)
    assert post.quantile("k", 0.5) == pytest.approx(0.25)  # a continuous one: as before
    for odd in ("kind", 3, ["kind"]):  # a record that is no dict of levels: linear, as before
        odd_post = gpmsa.Posterior(draws, info={"levels": odd})
        assert odd_post.quantile("kind", 0.5) == pytest.approx(0.5)


def test_calibrate_records_the_levels_and_its_quantiles_are_levels():
    _, emu, xo, yo = level_case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        post = gpmsa.calibrate(emu, xo, yo, n_samples=600, n_burn=100, n_chains=2, n_jobs=1,
                               seed=3)  # fmt: skip
    assert post.info["levels"] == {"kind": [0.0, 1.0, 2.0]}
    qs = post.quantile("kind", np.linspace(0.0, 1.0, 41))
    assert set(np.unique(qs)) <= {0.0, 1.0, 2.0}
    plain = gpmsa.calibrate(*_continuous_case(), n_samples=200, n_burn=50, n_chains=1, seed=1)
    assert "levels" not in plain.info


def _continuous_case():
    rng = np.random.default_rng(0)
    x, t = rng.random((30, 1)), rng.random((30, 1))
    emu = gpmsa.fit(gpmsa.SimData(x, t, np.sin(3 * x[:, 0]) + t[:, 0]), n_iter=200, seed=0)
    return emu, np.array([[0.3], [0.6]]), np.sin(3 * np.array([0.3, 0.6])) + 0.5


def test_a_study_records_the_levels_and_its_quantiles_are_levels():
    _, emu, xo, yo = level_case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        study = gpmsa.calibrate_study([emu, emu], [xo[:3], xo[3:]], [yo[:3], yo[3:]],
                                      shared=["kind", "k"], n_samples=300, n_burn=50,
                                      n_chains=1, seed=2)  # fmt: skip
    post = study.posterior
    assert post.info["levels"] == {"kind": [0.0, 1.0, 2.0]}
    assert set(np.unique(post.quantile("kind", np.linspace(0, 1, 41)))) <= {0.0, 1.0, 2.0}
