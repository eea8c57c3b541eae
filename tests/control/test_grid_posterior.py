"""GridPosterior: moments and quantiles of a gridded density."""

import numpy as np
import pytest
from scipy import stats

from control import ControlError, GridPosterior


def test_moments_and_quantiles_match_a_gaussian():
    grid = np.linspace(200, 600, 2001)
    post = GridPosterior(grid, stats.norm.pdf(grid, 420, 25))
    assert post.mean() == pytest.approx(420, abs=0.05)
    assert post.sd() == pytest.approx(25, rel=1e-3)
    for q in (0.05, 0.25, 0.5, 0.9):
        assert post.quantile(q) == pytest.approx(stats.norm.ppf(q, 420, 25), abs=0.3)
    lo, hi = post.interval(0.9)
    assert (lo, hi) == pytest.approx(stats.norm.interval(0.9, 420, 25), abs=0.3)
    assert post.prob_above(450) == pytest.approx(stats.norm.sf(450, 420, 25), abs=2e-3)


def test_samples_follow_the_posterior():
    grid = np.linspace(200, 600, 801)
    post = GridPosterior(grid, stats.norm.pdf(grid, 300, 20))
    draws = post.sample(20_000, np.random.default_rng(0))
    assert draws.mean() == pytest.approx(300, abs=0.6)
    assert draws.std() == pytest.approx(20, rel=0.03)


@pytest.mark.parametrize(
    ("grid", "mass", "match"),
    [
        ([1.0, 2.0], [0.0, 0.0], "not all zero"),
        ([1.0, 2.0], [np.nan, 1.0], "finite"),
        ([2.0, 1.0], [1.0, 1.0], "strictly increasing"),
        ([1.0, 2.0, 3.0], [1.0, 1.0], "equal length"),
    ],
)
def test_bad_input_raises(grid, mass, match):
    with pytest.raises(ControlError, match=match):
        GridPosterior(np.array(grid), np.array(mass))


def test_bad_quantile_level_raises():
    post = GridPosterior(np.array([1.0, 2.0, 3.0]), np.array([1.0, 1.0, 1.0]))
    with pytest.raises(ControlError, match="q must lie in"):
        post.quantile(1.5)
    with pytest.raises(ControlError, match="level must lie in"):
        post.interval(1.0)
