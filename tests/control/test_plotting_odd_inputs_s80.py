"""control's figures with odd but valid inputs (session 80 sweep): posterior draws a few ulps
apart, and a dark matplotlib style."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from control_doubles import plotted_run_and_track  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402

from control import ControlError  # noqa: E402
from control.plotting import plot_gd_trace, plot_posterior_grid  # noqa: E402


def test_posterior_draws_a_few_ulps_apart_get_a_range_about_their_value():
    """A span of 3 ulps was rounded to a range of 1e-13 that numpy refused: "Too many bins for
    data range. Cannot create 40 finite-sized bins"."""
    draws = 400.0 + np.spacing(400.0) * (np.arange(100) % 4)
    fig = plot_posterior_grid([(1.0, 400.0, draws)])
    assert fig.axes[0].get_xlim()[0] <= 300.0 and fig.axes[0].get_xlim()[1] >= 500.0
    heights = [p.get_height() for p in fig.axes[0].patches]
    assert max(heights) > 0
    equal = plot_posterior_grid([(1.0, 400.0, np.full(100, 400.0))])  # as for equal draws
    assert equal.axes[0].get_xlim() == fig.axes[0].get_xlim()
    spread = np.random.default_rng(0).normal(400.0, 20.0, 200)  # an ordinary spread: as before
    assert plot_posterior_grid([(1.0, 400.0, spread)]).axes[0].get_xlim()[0] > 300.0 - 50.0


def test_a_gd_range_narrower_than_the_bins_is_refused_naming_it():
    draws = np.random.default_rng(0).normal(400.0, 20.0, 50)
    with pytest.raises(ControlError, match=r"gd_range=\(400.0, 400.0000000000001\) is too narrow"):
        plot_posterior_grid([(1.0, 400.0, draws)], gd_range=(400.0, 400.0000000000001))
    assert plot_posterior_grid([(1.0, 400.0, draws)], gd_range=(399.0, 401.0)) is not None


def test_the_prescribed_gd_stays_visible_in_a_dark_style():
    """The prescribed GD and the true GD lines were black, on dark_background's black axes."""
    run, track = plotted_run_and_track()
    cells = [(1.0, 400.0, np.random.default_rng(0).normal(400.0, 20.0, 50))]
    with plt.style.context("dark_background"):
        trace = plot_gd_trace([run], track)
        grid = plot_posterior_grid(cells)
    steps = [line for line in trace.axes[0].lines if line.get_label() == "prescribed GD"]
    assert to_rgba(steps[0].get_color()) == to_rgba("white")
    assert to_rgba(grid.axes[0].lines[0].get_color()) == to_rgba("white")
    steps = [line for line in plot_gd_trace([run], track).axes[0].lines
             if line.get_label() == "prescribed GD"]  # fmt: skip
    assert to_rgba(steps[0].get_color()) == to_rgba("k")  # the default style: black, as before
