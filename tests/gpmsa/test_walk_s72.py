"""Session 72's walk through the new features as a SEPIA user: a separable design given in the
other nesting order (np.meshgrid's default) or with a grid rounded run by run is refused with
the way out; calibrate's tempered draws and `gpmsa info` record what judges the ladder; the
file's separable declaration is shown."""

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import GPMSAError


def _grid(indexing: str):
    """A 4 x 5 grid of (x, T) with a scalar output, rows in ``indexing``'s order."""
    X, T = np.meshgrid(np.linspace(0, 2, 4), np.linspace(100, 300, 5), indexing=indexing)
    x, t = X.reshape(-1, 1), T.reshape(-1, 1)
    return x, t, np.sin(2 * x) + (t / 200) ** 2


def test_separable_in_the_other_nesting_order_names_the_order_that_fits():
    x, t, y = _grid("xy")  # x varies fastest: the last factor, not the first
    with pytest.raises(GPMSAError, match=r"give separable=\[\['T'\], \['x'\]\]"):
        gpmsa.SimData(x, t, y, x_names=["x"], t_names=["T"], separable=True)
    sim = gpmsa.SimData(x, t, y, x_names=["x"], t_names=["T"], separable=[["T"], ["x"]])
    assert sim.separable == ((1,), (0,))
    order = np.random.default_rng(0).permutation(20)  # shuffled: no order fits, no hint
    with pytest.raises(GPMSAError, match=r"one order throughout\)$"):
        gpmsa.SimData(x[order], t[order], y[order], separable=True)


def test_separable_grid_rounded_run_by_run_is_named():
    x, t, y = _grid("ij")
    x = x + 1e-13 * np.random.default_rng(1).standard_normal(x.shape)
    with pytest.raises(GPMSAError, match=r"\[x0\]: points that agree to 1e-9 of the range"):
        gpmsa.SimData(x, t, y, separable=True)
    x, t, y = _grid("ij")
    with pytest.raises(GPMSAError, match=r"there are 19 runs$"):  # a run missing: no hint
        gpmsa.SimData(x[:-1], t[:-1], y[:-1], separable=True)


def test_tempered_calibrate_records_ladder_and_swap_rates():
    x, t, y = _grid("ij")
    emu = gpmsa.fit(gpmsa.SimData(x, t, y), n_iter=60, seed=0)
    post = gpmsa.calibrate(emu, [[1.0]], [[1.8]], n_samples=60, n_burn=10, fast=False,
                           temperatures=2, seed=0)  # fmt: skip
    assert post.info["temperatures"] == [1.0, 2.0] and post.info["swap_every"] == 1
    assert np.shape(post.info["swap_rate"]) == (1, 1)
    assert 0.0 <= post.info["swap_rate"][0][0] <= 1.0
