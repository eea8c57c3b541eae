"""A grid or level marginal's own ``ppf``, ``hdi`` and ``cdf`` refuse what `Posterior`'s refuse
(a q outside [0, 1], a level outside (0, 1), a NaN value) instead of clipping it to an end."""

import numpy as np
import pytest

from gpmsa import GPMSAError
from gpmsa.calibration.posterior import GridMarginal, LevelMarginal


def _grid() -> GridMarginal:
    return GridMarginal.from_log_density(np.linspace(0.0, 1.0, 5), np.zeros(5))


def _levels() -> LevelMarginal:
    return LevelMarginal.from_probabilities([1.0, 2.0, 3.0], [0.2, 0.5, 0.3])


MARGINALS = [pytest.param(_grid, id="grid"), pytest.param(_levels, id="levels")]


@pytest.mark.parametrize("make", MARGINALS)
@pytest.mark.parametrize("q", [1.5, -0.1, np.nan, [0.5, 2.0], np.inf])
def test_ppf_refuses_a_q_outside_0_1(make, q):
    with pytest.raises(GPMSAError, match=r"q must lie in \[0, 1\]"):
        make().ppf(q)


@pytest.mark.parametrize("make", MARGINALS)
@pytest.mark.parametrize("level", [1.5, 0, 1.0, -0.2, np.nan, "0.9", True])
def test_hdi_refuses_a_level_outside_0_1(make, level):
    with pytest.raises(GPMSAError, match=r"level must be a number in \(0, 1\)"):
        make().hdi(level)


@pytest.mark.parametrize("make", MARGINALS)
@pytest.mark.parametrize("value", [np.nan, [0.5, np.nan]])
def test_cdf_refuses_a_nan_value(make, value):
    with pytest.raises(GPMSAError, match="value must not be NaN"):
        make().cdf(value)


def test_the_ends_and_the_edges_of_0_1_are_still_taken():
    grid, levels = _grid(), _levels()
    assert grid.ppf(0.0) == 0.0 and grid.ppf(1.0) == 1.0 and grid.ppf(0.25) == 0.25
    assert levels.ppf(0.0) == 1.0 and levels.ppf(1.0) == 3.0 and levels.ppf(0.7) == 2.0
    assert grid.cdf(np.inf) == 1.0 and grid.cdf(-np.inf) == 0.0
    assert levels.cdf(np.inf) == 1.0 and levels.cdf(-np.inf) == 0.0
    lo, hi = grid.hdi(0.5)  # a uniform density: any half-width interval, the first tried
    assert hi - lo == pytest.approx(0.5)
    assert levels.hdi(0.5) == (2.0, 2.0) and levels.hdi(0.8) == (2.0, 3.0)


def test_a_float32_level_is_read_as_its_float64_value():
    """(Before, a numpy float32 level went uncached through float32 tail arithmetic.)"""
    grid = _grid()
    assert grid.hdi(np.float32(0.5)) == grid.hdi(float(np.float32(0.5)))


@pytest.mark.parametrize("make", MARGINALS)
def test_an_empty_q_is_named_as_empty(make):
    with pytest.raises(GPMSAError, match=r"^q must hold at least one probability, got \[\]$"):
        make().ppf([])
