"""plots.prediction_bands draws a functional output along its grid in increasing order.

An observation grid (and so the default grid of ``full_prediction``) may come in any order; the
bands, means and observed values must still be drawn against the grid sorted, each value staying
with its own grid point (not a zigzag polygon through the grid in the given order).
"""

from __future__ import annotations

import warnings
from functools import cache

import matplotlib
import numpy as np

import gpmsa
from gpmsa import plots

matplotlib.use("Agg")

GRID = np.linspace(0.0, 1.0, 8)
OBS_GRID = GRID[[5, 1, 7, 0, 3]]  # an observation grid in no order (ObsData allows it)


def _sim(x: np.ndarray, t: np.ndarray, grid: np.ndarray) -> np.ndarray:
    return np.exp(-np.outer(t * (1.0 + 0.5 * x), grid))


@cache
def _prediction() -> tuple[gpmsa.FullPrediction, np.ndarray]:
    """A full prediction at 2 new x on the unsorted observation grid, and observed values."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(0.0, 1.0, 20), rng.uniform(0.5, 2.0, 20)
    data = gpmsa.SimData(x=x[:, None], t=t[:, None], y=_sim(x, t, GRID), index=GRID,
                         x_names=["x"], t_names=["t"])  # fmt: skip
    xo = np.linspace(0.1, 0.9, 4)
    obs = gpmsa.ObsData(x=xo[:, None], y=_sim(xo, np.full(4, 1.2), OBS_GRID), index=OBS_GRID)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a short chain
        emu = gpmsa.fit(data, obs, n_iter=40, tune=False, seed=0, discrepancy="constant")
    x_new = np.array([[0.3], [0.6]])
    pred = gpmsa.full_prediction(emu, obs, x_new, n_draws=20, n_rlz=2, seed=1)
    return pred, _sim(x_new[:, 0], np.full(2, 1.2), OBS_GRID)


def test_unsorted_grid_is_drawn_in_increasing_order_with_its_values():
    pred, observed = _prediction()
    np.testing.assert_array_equal(pred.grid, OBS_GRID)  # the default grid keeps the obs order
    order = np.argsort(OBS_GRID)
    fig = plots.prediction_bands(pred, observed=observed)
    for c in range(2):  # one column per new x
        top, bottom = fig.axes[c], fig.axes[2 + c]
        eta_line, obs_line = top.lines
        np.testing.assert_array_equal(eta_line.get_xdata(), OBS_GRID[order])
        np.testing.assert_allclose(eta_line.get_ydata(), pred.mean("eta")[c, order], rtol=1e-12)
        np.testing.assert_array_equal(obs_line.get_xdata(), OBS_GRID[order])
        np.testing.assert_array_equal(obs_line.get_ydata(), observed[c, order])
        delta_line = bottom.lines[0]
        np.testing.assert_allclose(delta_line.get_ydata(), pred.mean("delta")[c, order],
                                   rtol=1e-12, atol=1e-15)  # fmt: skip
        lo, hi = pred.interval("y", 0.9)
        n = OBS_GRID.size  # a band's path: a start point, the lower edge, then the upper back
        band = top.collections[0].get_paths()[0].vertices
        np.testing.assert_array_equal(band[1 : 1 + n, 0], OBS_GRID[order])
        np.testing.assert_allclose(band[1 : 1 + n, 1], lo[c, order], rtol=1e-12)
        np.testing.assert_allclose(band[n + 2 : 2 * n + 2, 1], hi[c, order][::-1], rtol=1e-12)
