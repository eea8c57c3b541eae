"""A heavy-tailed one-parameter posterior cut by a constraint just past its peak: what is left
falls steeply from the cut, then slowly, so its sd (the tails') is 2.2-2.8 times the width of
its core. Refinement measured a peak by its sd and stopped at 4 spacings per sd, with the core
on 1-2 cells per e-fold: quantiles 0.06-0.15 sd and the cdf 0.002-0.006 off a dense grid,
silently. A peak's spread is now the smaller of its sd and IQR / 1.349 (`grid._spread`)."""

import numpy as np
import pytest
from test_grid_one_param_edges_s57 import (
    LEVELS,
    dense_reference,
    observations,
    vague_lamos_emulator,
)

from gpmsa import Calibrator
from gpmsa.calibration.grid import _spread


@pytest.mark.parametrize(("n", "cut", "n_grid"), [(2, 0.406, 33), (2, 0.42, 129), (3, 0.42, 33)])
def test_a_heavy_tail_cut_past_its_peak_is_refined_over_its_core(n, cut, n_grid):
    """Were 0.154 / 0.125 / 0.059 sd off in the quantiles, 0.0055 / 0.0039 / 0.0024 in the cdf."""
    x, y = observations(n)
    cal = Calibrator(vague_lamos_emulator(), n_grid=n_grid, constraint=lambda t: t[0] >= cut)
    post = cal.update(x, y)
    sd, quantiles = dense_reference(n, around=0.4, cut=cut)
    assert np.max(np.abs(post.quantile("t", LEVELS) - quantiles)) < 0.04 * sd
    assert np.max(np.abs(post.grids["t"].cdf(quantiles) - LEVELS)) < 0.0015


def test_the_spread_is_the_sd_of_a_light_tailed_peak():
    """A Gaussian's spread is its sd (IQR / 1.349 is larger on a grid by at most a few %); a
    Student-t's with 1.5 dof is its IQR's, well under its sd."""
    axis = np.linspace(-10.0, 10.0, 4001)
    gauss = np.exp(-0.5 * axis**2)
    assert _spread(axis, gauss) == pytest.approx(1.0, rel=1e-3)
    heavy = (1.0 + axis**2 / 1.5) ** -1.25
    sd = np.sqrt(heavy @ axis**2 / heavy.sum())
    assert _spread(axis, heavy) < 0.65 * sd  # 1.25 against 2.07 (the axis cuts its tails)
