"""A bare matplotlib Figure (no pyplot state, no GUI backend), the style's ink colour, the
colours of series told apart by colour, the histograms' bin check, the axes' labels, and which
output indices draw as maps."""

from __future__ import annotations

import numpy as np

from gpmsa.errors import GPMSAError
from gpmsa.limits import BYTES_PER_HISTOGRAM_BIN, check_memory
from gpmsa.model.data import check_count


def figure(width: float, height: float):
    """A constrained-layout Figure of the given size in inches (matplotlib imported here)."""
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def ink() -> str:
    """The style's foreground colour (``rcParams["text.color"]``) for what is drawn as data
    rather than as a band (observations, a prescribed value, error bars): black in matplotlib's
    default style, as "k" was, and white in ``plt.style.use("dark_background")``, where black
    would not show on the black axes."""
    from matplotlib import rcParams

    return rcParams["text.color"]


def series_colours(n: int) -> list[str]:
    """The colours of ``n`` series that a legend tells apart by colour alone (chains,
    experiments): the style's colour cycle, ``"C0"``, ``"C1"``, ..., where its first
    ``min(n, 10)`` colours differ from each other, else matplotlib's default ten ("tab:blue",
    ...; a style or an ``rcParams["axes.prop_cycle"]`` of one colour drew every series, and its
    legend entry, in that one colour). Beyond ten series colours repeat, as matplotlib's do."""
    from matplotlib import rcParams
    from matplotlib.colors import TABLEAU_COLORS, to_rgba

    first = rcParams["axes.prop_cycle"].by_key().get("color", [])[: min(n, 10)]
    if len({to_rgba(c) for c in first}) == min(n, 10):
        return [f"C{k}" for k in range(n)]
    tab10 = list(TABLEAU_COLORS)
    return [tab10[k % 10] for k in range(n)]


def check_bins(bins, n_hist: int, what: str) -> int:
    """``bins`` as an int >= 1 whose ``n_hist`` histograms fit ``gpmsa.limits.MAX_MEMORY_BYTES``
    (GPMSAError, or ResourceLimitError stating the limit, otherwise)."""
    bins = check_count(bins, "bins")
    check_memory(
        BYTES_PER_HISTOGRAM_BIN * bins * n_hist, f"{what}: {n_hist} histogram(s) of {bins} bins"
    )
    return bins


def axis_label(name: str, unit: str) -> str:
    """``name (unit)``, every figure's label of a quantity, or the name alone without a unit."""
    return f"{name} ({unit})" if unit else name


def index_columns(names, units, grid) -> tuple[tuple[str, str], ...]:
    """(name, unit) of each column of an output index ``grid`` ((l,), (l, d) or None: one
    column) as ``SimData(index_names=, index_units=)`` gave them (None: "output index" for one
    column, "output index[:, k]" for column k of several; no unit)."""
    d = np.shape(grid)[1] if np.ndim(grid) == 2 else 1
    default = ("output index",) if d == 1 else tuple(f"output index[:, {k}]" for k in range(d))
    names = default if names is None else tuple(names)
    units = ("",) * d if units is None else tuple(units)
    return tuple(zip(names, units, strict=True))


def index_labels(names, units, grid) -> tuple[str, ...]:
    """The axis labels of an output index ``grid``: ``name (unit)`` per column
    (`index_columns`)."""
    return tuple(axis_label(n, u) for n, u in index_columns(names, units, grid))


def is_map(grid, what: str) -> bool:
    """Whether the plot ``what`` draws maps over an output index of two columns (l, 2)
    (SEPIA's (time, angle) y_ind) rather than curves along one (None or (l,)); GPMSAError for
    three or more columns, which neither a curve nor a map shows."""
    if grid is None or np.ndim(grid) != 2:
        return False
    l, d = np.shape(grid)
    if d != 2:
        raise GPMSAError(
            f"{what} draws along a one-column output index or maps over a two-column one; this "
            f"one has {l} points in {d} columns: plot slices of the values against two of its "
            "columns yourself (e.g. matplotlib's tricontourf over emu.standardizer.grid)"
        )
    return True
