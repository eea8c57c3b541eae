"""Session 73: ``gpmsa.plots.main_effect_curves`` draws a categorical input's main effect as
points at its levels with the intervals as error bars (no line joining the levels, which would
suggest values between them), its levels as the axis's ticks (named by ``level_names``); a
continuous input's panel is unchanged. The effect functions are evaluated at the levels only."""

from __future__ import annotations

import dataclasses

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from _sens_cases import categorical_emulator  # noqa: E402
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402
from matplotlib.container import ErrorbarContainer  # noqa: E402

import gpmsa  # noqa: E402
from gpmsa import GPMSAError  # noqa: E402


@pytest.fixture(scope="module")
def sens():
    emu = categorical_emulator(None)
    out = gpmsa.sensitivity(emu, draws=False, main_effect_grid=5, effect_variance=True)
    # a spread over draws: 4 shifted copies of the point estimate's curves
    shift = np.array([-0.2, -0.1, 0.1, 0.3])[:, None, None, None]
    return dataclasses.replace(out, main_effect=out.main_effect + shift,
                               main_effect_variance=np.repeat(out.main_effect_variance, 4, 0),
                               draw_index=np.arange(4))  # fmt: skip


def _finite_lines(ax):
    return [ln for ln in ax.get_lines() if np.isfinite(ln.get_xdata()).sum() > 1
            and ln.get_linestyle() not in ("None", "", " ", ":")]  # fmt: skip


def test_the_categorical_input_is_evaluated_at_its_levels_and_marked(sens):
    assert sens.categorical == ("kind",)
    np.testing.assert_array_equal(sens.effect_grid[:, 1], [0, 1, 3, np.nan, np.nan])
    assert sens.bounds["kind"] == (0, 1, 3)


def test_a_categorical_panel_has_points_and_error_bars_at_its_levels(sens):
    fig = gpmsa.plots.main_effect_curves(sens, level=0.9)
    ax_x, ax_kind = fig.axes[0], fig.axes[1]
    # the continuous input: a line over its 5 grid points and two bands, as before
    assert len(_finite_lines(ax_x)) == 1
    assert sum(isinstance(c, PolyCollection) for c in ax_x.collections) == 2
    # the categorical input: no line joining the levels, no band between them
    assert _finite_lines(ax_kind) == []
    assert not any(isinstance(c, PolyCollection) for c in ax_kind.collections)
    pts = [ln for ln in ax_kind.get_lines() if ln.get_marker() == "o"]
    assert len(pts) == 1
    np.testing.assert_array_equal(pts[0].get_xdata(), [0, 1, 3])
    cur = sens.main_effect[:, :3, 0, 1]
    np.testing.assert_allclose(pts[0].get_ydata(), cur.mean(axis=0))
    bars = [c for c in ax_kind.containers if isinstance(c, ErrorbarContainer)]
    assert len(bars) == 2  # the GP's (wider) and the draws' interval
    lo, hi = np.quantile(cur, [0.05, 0.95], axis=0)
    segs = bars[1].lines[2][0]
    assert isinstance(segs, LineCollection)
    ends = np.array([[s[0, 1], s[1, 1]] for s in segs.get_segments()])
    np.testing.assert_allclose(np.sort(ends, axis=1), np.column_stack([lo, hi]))
    gp = np.array([[s[0, 1], s[1, 1]] for s in bars[0].lines[2][0].get_segments()])
    assert np.all(gp[:, 0] <= lo) and np.all(gp[:, 1] >= hi)
    np.testing.assert_array_equal(ax_kind.get_xticks(), [0, 1, 3])
    assert [t.get_text() for t in ax_kind.get_xticklabels()] == ["0", "1", "3"]
    plt.close(fig)


def test_level_names_label_the_ticks_and_bad_ones_are_refused(sens):
    fig = gpmsa.plots.main_effect_curves(sens, level_names={"kind": {0: "grass", 1: "gravel",
                                                                     3: "tarmac"}})  # fmt: skip
    assert [t.get_text() for t in fig.axes[1].get_xticklabels()] == ["grass", "gravel", "tarmac"]
    plt.close(fig)
    fig = gpmsa.plots.main_effect_curves(sens, level_names={"kind": ["a", "b", "c"]})
    assert [t.get_text() for t in fig.axes[1].get_xticklabels()] == ["a", "b", "c"]
    plt.close(fig)
    for bad, msg in (({"x": ["a", "b"]}, "'x', not a varied categorical input"),
                     ({"kind": {0: "a", 1: "b"}}, "no name for levels [3]"),
                     ({"kind": {0: "a", 1: "b", 5: "c"}}, "[5] are not among them"),
                     ({"kind": ["a", "b"]}, "a list of 3 names"),
                     (["a"], "level_names must be None or a dict")):  # fmt: skip
        with pytest.raises(GPMSAError, match=msg.replace("[", r"\[").replace("]", r"\]")):
            gpmsa.plots.main_effect_curves(sens, level_names=bad)
