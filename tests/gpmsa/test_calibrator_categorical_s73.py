"""The online Calibrator with a categorical calibration parameter (session 73).

It refused one (grid and MCMC alike, hence ``gpmsa calibrate`` and the observation plots). Its
grid now takes the levels as the categorical axis's nodes (exact: no value between levels), the
continuous parameter on ``n_grid`` nodes per level; its MCMC is ``gpmsa.calibrate``'s with the
joint level move. The trading-off case (``_level_cases``: y = sin(3x) + k + 0.5 kind) has
P(kind) = 0.717 / 0.283 / 0 by a brute-force grid.
"""

import warnings

import numpy as np
import pytest
from _level_cases import level_case

import gpmsa
from gpmsa.cli.main import main


@pytest.fixture(scope="module")
def case():
    return level_case()


@pytest.fixture(scope="module")
def grid_post(case):
    _, emu, xo, yo = case
    return gpmsa.Calibrator(emu, seed=1).update(xo, yo)


def test_the_grid_gives_the_brute_force_level_probabilities(grid_post):
    from gpmsa.calibration.posterior import LevelMarginal

    post = grid_post
    assert post.info["method"] == "grid" and post.info["levels"] == {"kind": [0.0, 1.0, 2.0]}
    kind = post.grids["kind"]
    assert isinstance(kind, LevelMarginal)
    np.testing.assert_allclose(kind.density, [0.717, 0.283, 0.0], atol=0.005)
    draws = post.samples["kind"]
    assert set(np.unique(draws)) <= {0.0, 1.0, 2.0}  # exactly the level codes
    np.testing.assert_allclose(np.mean(draws == 0.0), kind.density[0], atol=0.03)
    # given its level, k is where that level explains the data (0.9 and 0.4)
    k = post.samples["k"]
    assert abs(np.mean(k[draws == 0]) - 0.9) < 0.03 and abs(np.mean(k[draws == 1]) - 0.4) < 0.03
    assert post.info["resolution"][1] == np.inf and post.info["resolution"][0] > 1.5


def test_a_categorical_summary_is_in_levels(grid_post):
    post = grid_post
    q = post.quantile("kind", [0.0, 0.05, 0.5, 0.716, 0.718, 0.95, 1.0])
    np.testing.assert_array_equal(q, [0, 0, 0, 0, 1, 1, 2])  # level 2 has mass 4e-6
    assert post.interval("kind", 0.9) == (0.0, 1.0) and post.hdi("kind", 0.5) == (0.0, 0.0)
    p1 = post.grids["kind"].density[1] + 2 * post.grids["kind"].density[2]
    assert post.mean("kind") == pytest.approx(p1)  # the mean of the codes, as MCMC's draws'
    assert post.prob_above("kind", 0.5) == pytest.approx(1 - post.grids["kind"].density[0])
    # k's marginal: the two levels' densities summed, bimodal
    assert post.quantile("k", 0.05) < 0.45 and post.quantile("k", 0.5) > 0.85
    post.plot("kind")


def test_the_mcmc_mode_uses_the_level_move(case, grid_post):
    _, emu, xo, yo = case
    cal = gpmsa.Calibrator(emu, method="mcmc", seed=2,
                           mcmc_options={"n_samples": 1500, "n_burn": 300, "n_chains": 2,
                                         "n_jobs": 1, "fast": False})  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        post = cal.update(xo, yo)
    kind = post.samples["kind"]
    got = [np.mean(kind == v) for v in (0, 1, 2)]
    np.testing.assert_allclose(got, grid_post.grids["kind"].density, atol=0.06)


def test_an_all_categorical_theta_is_a_finite_set(case):
    """One categorical parameter: the posterior is a probability per level (no other node),
    as calibrate(fast=False)'s draws give it."""
    rng = np.random.default_rng(2)
    x, t = rng.random((45, 1)), (np.arange(45) % 3)[:, None]
    sim = gpmsa.SimData(x, t, np.sin(3 * x[:, 0]) + 0.5 * t[:, 0], x_names=["s"],
                        t_names=["kind"], t_categorical=["kind"])  # fmt: skip
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[1.0], [1.0]], "lamUz": [1.0],
                                           "lamWs": [1e3], "lamWOs": [1e3]})  # fmt: skip
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    yo = np.sin(3 * xo[:, 0]) + 0.25 + rng.normal(0, 0.05, 6)  # between kinds 0 and 1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)  # no level explains it
        cal = gpmsa.Calibrator(emu, seed=1)
        post = cal.update(xo, yo)
        ref = gpmsa.calibrate(emu, xo, yo, seed=1, n_samples=3000, n_burn=300, fast=False)
    np.testing.assert_array_equal(cal.theta_grid, [0.0, 1.0, 2.0])
    p = post.grids["kind"].density
    assert 0.2 < p[0] < 0.3 and post.info["log_evidence"] is not None  # 0.249
    np.testing.assert_allclose([np.mean(ref.samples["kind"] == v) for v in (0, 1, 2)], p,
                               atol=0.05)  # fmt: skip
    assert set(np.unique(post.samples["kind"])) <= {0.0, 1.0, 2.0}


def test_a_gridded_prior_and_a_callable_agree(case):
    _, emu, xo, yo = case
    cal = gpmsa.Calibrator(emu, seed=1)
    prior = lambda th: np.where(th[:, 1] == 1.0, 0.0, -3.0)  # noqa: E731
    a = cal.update(xo, yo, prior=prior)
    b = cal.update(xo, yo, prior=prior(cal.theta_grid).reshape(129, 3))
    np.testing.assert_allclose(a.grids["kind"].density, b.grids["kind"].density)
    assert a.grids["kind"].density[1] > 0.85  # e^3 more prior mass on kind 1


def test_what_the_grid_does_not_do_is_refused_by_name(case):
    _, emu, *_ = case
    with pytest.raises(gpmsa.GPMSAError, match="categorical and a continuous.*no constraint"):
        gpmsa.Calibrator(emu, method="grid", constraint=lambda th: th[0] < 0.8)
    cal = gpmsa.Calibrator(emu, constraint=lambda th: th[0] < 0.8)  # auto: MCMC
    assert cal.method == "mcmc"


def test_the_command_and_the_plots_take_such_a_file(case, tmp_path, capsys):
    _, emu, xo, yo = case
    path = str(emu.save(tmp_path / "kind.gpmsa"))
    assert main(["calibrate", path, "--x", "s=0.5", "--y", "y0=1.4", "--seed", "1"]) == 0
    out = capsys.readouterr().out
    assert "posterior (grid" in out and "kind" in out
    obs = gpmsa.ObsData(x=xo, y=yo[:, None])
    gpmsa.plots.obs_projection(emu, obs)
    gpmsa.plots.weight_pairs(emu, obs)


def test_two_categorical_parameters_with_a_constraint():
    """Two categorical parameters: the grid is the pairs of levels; a constraint removes a
    pair exactly (zero mass, never drawn)."""
    rng = np.random.default_rng(0)
    x, t = rng.random((36, 1)), np.column_stack([np.arange(36) % 3, (np.arange(36) // 3) % 2])
    f = lambda x, t: np.sin(3 * x[:, 0]) + 0.5 * t[:, 0] - 0.3 * t[:, 1]  # noqa: E731
    sim = gpmsa.SimData(x, t, f(x, t), x_names=["s"], t_names=["a", "b"],
                        t_categorical=["a", "b"])  # fmt: skip
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[1.0], [1.0], [1.0]], "lamUz": [1.0],
                                           "lamWs": [1e3], "lamWOs": [1e3]})  # fmt: skip
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    yo = f(xo, np.tile([1, 1], (6, 1))) + rng.normal(0, 0.05, 6)
    cal = gpmsa.Calibrator(emu, seed=1)
    assert cal.method == "grid" and cal.theta_grid.shape == (6, 2)
    post = cal.update(xo, yo)
    assert post.grids["a"].density[1] > 0.99 and post.grids["b"].density[1] > 0.99
    cut = gpmsa.Calibrator(emu, seed=1, constraint=lambda th: not (th[0] == 1 and th[1] == 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
        post = cut.update(xo, yo)
    pairs = np.column_stack([post.samples["a"], post.samples["b"]])
    assert not np.any((pairs[:, 0] == 1) & (pairs[:, 1] == 1))
    assert set(np.unique(pairs)) <= {0.0, 1.0, 2.0}
