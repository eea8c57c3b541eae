"""GridMarginal and Posterior.prob_above at their edges (mutation testing found each one free):
the CDF in the last cell, P(X > value) of draws that hit the value, a grid ending at inf."""

import numpy as np
import pytest

from gpmsa import GPMSAError, Posterior
from gpmsa.calibration.posterior import GridMarginal


def test_the_cdf_and_prob_above_hold_the_last_cells_mass():
    """A uniform density on [0, 1] (5 nodes): P(X <= x) = x in every cell, the last one too."""
    g = GridMarginal.from_log_density(np.linspace(0.0, 1.0, 5), np.zeros(5))
    x = np.array([0.1, 0.3, 0.6, 0.8, 0.875, 0.99, 1.0])
    np.testing.assert_allclose(g.cdf(x), x, rtol=1e-12)
    post = Posterior(grids={"theta": g}, draw=lambda: {}, info={"names": ("theta",)})
    assert post.prob_above("theta", 0.875) == pytest.approx(0.125, rel=1e-12)
    assert post.prob_above("theta", 1.0) == 0.0


def test_prob_above_of_draws_excludes_the_value_itself():
    """P(X > value): draws equal to the value (a categorical level) do not count."""
    post = Posterior(samples={"level": np.array([1.0, 1.0, 2.0, 3.0])})
    assert post.prob_above("level", 2.0) == 0.25
    assert post.prob_above("level", 3.0) == 0.0


@pytest.mark.parametrize("nodes", [[0.0, 1.0, np.inf], [-np.inf, 0.0, 1.0]])
def test_a_grid_with_an_infinite_end_is_refused(nodes):
    with pytest.raises(GPMSAError, match="finite and strictly increasing"):
        GridMarginal.from_log_density(np.array(nodes), np.zeros(3))
