"""The Calibrator's grid with a categorical and a continuous calibration parameter refines the
continuous axis per level (session 73).

Before, that grid was never refined: a conditional density narrower than the node spacing was
read on ``n_grid`` nodes per level (a warning; the user had to raise ``n_grid``). With
``n_grid=17`` on the narrow case below, P(kind) was 0.707 / 0.293 against a dense grid's
(4,097 nodes per level) 0.173 / 0.827, and k's sd given a level 0.0133 / 0.0250 against
0.0083 / 0.0063. Now each level's axis is refined as one parameter's is
(``grid.refined_axis``)."""

import warnings

import numpy as np
import pytest
from _level_cases import level_case, level_function

import gpmsa


def _kind_first(x, t):
    return np.sin(3 * x[:, 0]) + t[:, 1] + 0.5 * t[:, 0]


@pytest.fixture(scope="module")
def narrow():
    """The categorical parameter first (kind, k), fixed emulator parameters, six observations
    with noise 0.002 at kind 1, k = 0.4 (kind 0 at k = 0.9 fits alike): k's sd given a level
    0.006-0.008 of its range."""
    rng = np.random.default_rng(2)
    x = rng.random((60, 1))
    t = np.column_stack([np.arange(60) % 3, rng.random(60)])
    sim = gpmsa.SimData(x, t, _kind_first(x, t), x_names=["s"], t_names=["kind", "k"],
                        t_categorical=["kind"])  # fmt: skip
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[2.0], [1.0], [1.0]], "lamUz": [1.0],
                                           "lamWs": [1e4], "lamWOs": [1e5]})  # fmt: skip
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    yo = _kind_first(xo, np.tile([1, 0.4], (6, 1))) + rng.normal(0, 0.002, 6)
    return emu, xo, yo


def _given(level: float):
    """A prior that keeps one level: the posterior of k is its conditional given that level."""
    return lambda th: np.where(th[:, 0] == level, 0.0, -np.inf)


def test_a_narrow_conditional_is_resolved_without_a_larger_grid(narrow):
    emu, xo, yo = narrow
    dense = gpmsa.Calibrator(emu, n_grid=4097, seed=1)
    cal = gpmsa.Calibrator(emu, n_grid=17, seed=1)
    ref = dense.update(xo, yo)
    assert not ref.info["refined"]  # the reference resolves it as it is
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # resolved: no warning
        post = cal.update(xo, yo)
    assert post.info["refined"] and post.info["resolution"][1] > 4.0
    np.testing.assert_allclose(post.grids["kind"].density, ref.grids["kind"].density,
                               atol=2e-5)  # fmt: skip
    assert post.grids["kind"].density[1] == pytest.approx(0.8268, abs=2e-4)
    assert post.mean("k") == pytest.approx(ref.mean("k"), abs=1e-5)
    assert post.sd("k") == pytest.approx(ref.sd("k"), rel=1e-3)
    for level in (0.0, 1.0):  # the conditionals, exact (trapezoid) moments
        a = cal.update(xo, yo, prior=_given(level))
        b = dense.update(xo, yo, prior=_given(level))
        assert a.mean("k") == pytest.approx(b.mean("k"), abs=1e-5)
        assert a.sd("k") == pytest.approx(b.sd("k"), rel=5e-3)
    # the draws: a level, then k from its refined conditional, lamOs at its refined nodes
    got, want = post.samples, ref.samples
    for level in (0.0, 1.0):
        g, w = got["kind"] == level, want["kind"] == level
        assert np.mean(got["k"][g]) == pytest.approx(np.mean(want["k"][w]), abs=1e-3)
        assert np.std(got["k"][g]) == pytest.approx(np.std(want["k"][w]), rel=0.05)
        assert np.mean(got["lamOs"][g]) == pytest.approx(np.mean(want["lamOs"][w]), rel=0.1)


def test_the_trading_off_case_agrees_with_a_dense_grid():
    """kind second (k, kind): on the default grid (129 nodes per level) the draws of k given a
    level had an sd 5-8 % too wide (linear between nodes), with a warning; refined, they agree
    with 4,097 nodes per level."""
    _, emu, _, _ = level_case()
    rng = np.random.default_rng(3)
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    yo = level_function(xo, np.tile([0.4, 1], (6, 1))) + rng.normal(0, 0.002, 6)
    ref = gpmsa.Calibrator(emu, n_grid=4097, seed=1).update(xo, yo)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        post = gpmsa.Calibrator(emu, seed=1).update(xo, yo)
    assert post.info["refined"] and post.info["n_nodes"] > 3 * 129
    np.testing.assert_allclose(post.grids["kind"].density, ref.grids["kind"].density,
                               atol=2e-5)  # fmt: skip
    for level in (0.0, 1.0):  # the same seed: the same levels, nearly the same k
        g = post.samples["kind"] == level
        np.testing.assert_array_equal(g, ref.samples["kind"] == level)
        assert np.mean(post.samples["k"][g]) == pytest.approx(np.mean(ref.samples["k"][g]),
                                                              abs=2e-4)  # fmt: skip
        assert np.std(post.samples["k"][g]) == pytest.approx(np.std(ref.samples["k"][g]),
                                                             rel=0.01)  # fmt: skip
    assert post.quantile("k", [0.05, 0.5, 0.95]) == pytest.approx(
        ref.quantile("k", [0.05, 0.5, 0.95]), abs=2e-4
    )


def test_a_gridded_prior_is_interpolated_along_a_refined_level(narrow):
    """A gridded prior (here levels x n_grid: kind is the first parameter) is interpolated along
    each level's nodes onto its refined axis: it gives the callable's posterior."""
    emu, xo, yo = narrow
    cal = gpmsa.Calibrator(emu, n_grid=17, seed=1)
    prior = lambda th: -0.5 * ((th[:, 1] - 0.5) / 0.3) ** 2 - (th[:, 0] == 0.0)  # noqa: E731
    a = cal.update(xo, yo, prior=prior)
    b = cal.update(xo, yo, prior=prior(cal.theta_grid).reshape(3, 17))
    assert a.info["refined"] and b.info["refined"]
    np.testing.assert_allclose(b.grids["kind"].density, a.grids["kind"].density, atol=1e-4)
    assert b.mean("k") == pytest.approx(a.mean("k"), abs=1e-4)
