"""plot_posterior_grid with float32 draws a few of their ulps apart: the range is chosen and
checked in float64, but numpy spaced the 40 bins in the draws' float32 and refused them ("Too
many bins for data range")."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

from control.plotting import plot_posterior_grid  # noqa: E402


def test_float32_draws_a_few_ulps_apart_are_drawn():
    v = np.float32(400.0)
    draws = (v + np.spacing(v) * (np.arange(100) % 4)).astype(np.float32)
    fig = plot_posterior_grid([(1.0, 400.0, draws)])  # before: ValueError from numpy
    patches = fig.axes[0].patches
    assert len(patches) == 40
    widths = sum(p.get_width() * p.get_height() for p in patches)
    np.testing.assert_allclose(widths, 1.0, rtol=1e-9)  # a density over the drawn range
    same = plot_posterior_grid([(1.0, 400.0, draws.astype(np.float64))])  # as float64 draws
    assert [p.get_height() for p in same.axes[0].patches] == [p.get_height() for p in patches]
