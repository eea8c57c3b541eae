"""plot_posterior_grid with a sparse set of (v, GD) cells: a missing cell was an empty framed
panel (ticks and all, nothing said), a column whose top cell was missing had no speed title,
and one whose bottom cell was missing no GD tick labels."""

import matplotlib

matplotlib.use("Agg")

import io  # noqa: E402

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from control.plotting import plot_posterior_grid  # noqa: E402


def cells():
    """Two of four cells: (1 m/s, GD 300) and (2 m/s, GD 500)."""
    rng = np.random.default_rng(0)
    return [(1.0, 300.0, rng.normal(300.0, 20.0, 200)), (2.0, 500.0, rng.normal(500.0, 20.0, 200))]


def texts(ax) -> list[str]:
    return [t.get_text() for t in ax.texts]


def test_a_missing_cell_is_marked_and_every_row_and_column_labelled():
    before = plt.get_fignums()
    fig = plot_posterior_grid(cells())
    assert plt.get_fignums() == before  # no pyplot figure kept open
    axes = np.array(fig.axes).reshape(2, 2)  # rows GD 300, 500; columns 1, 2 m/s
    for r, c in ((0, 0), (1, 1)):  # drawn: histogram and axes
        assert axes[r, c].axison and len(axes[r, c].patches) == 40 and not axes[r, c].texts
    for (r, c), (v, gd) in (((0, 1), (2, 300)), ((1, 0), (1, 500))):  # missing: said so
        assert not axes[r, c].axison and not axes[r, c].patches
        assert texts(axes[r, c]) == [f"no data\nv = {v} m/s, GD {gd}"]
    assert [ax.get_title() for ax in axes[0]] == ["v = 1 m/s", "v = 2 m/s"]
    assert axes[0, 0].get_ylabel() == "GD 300"
    # each column's lowest drawn panel carries the GD axis: its tick labels and its label
    for ax in (axes[0, 0], axes[1, 1]):
        assert ax.get_xlabel() == "GD (1e-6 m$^3$)"
        assert ax.xaxis.get_tick_params()["labelbottom"]
    fig.savefig(io.BytesIO(), format="png")  # draws on Agg


def test_a_full_grid_is_drawn_as_before():
    rng = np.random.default_rng(1)
    full = [(v, gd, rng.normal(gd, 20.0, 100)) for v in (1.0, 2.0) for gd in (300.0, 500.0)]
    axes = np.array(plot_posterior_grid(full).axes).reshape(2, 2)
    assert all(ax.axison and len(ax.patches) == 40 and not ax.texts for ax in axes.flat)
    label = "GD (1e-6 m$^3$)"
    assert [ax.get_xlabel() for ax in axes.flat] == ["", "", label, label]
    assert [ax.xaxis.get_tick_params()["labelbottom"] for ax in axes.flat] == [
        False, False, True, True
    ]  # fmt: skip
