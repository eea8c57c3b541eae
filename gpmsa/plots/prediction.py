"""Calibrated prediction bands (simulator, simulator + discrepancy, observation) against data."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from gpmsa.errors import GPMSAError
from gpmsa.model.data import ObsData, as_float, check_count, check_finite, check_level
from gpmsa.plots import _maps
from gpmsa.plots._figure import axis_label, figure, index_labels, ink, is_map, series_colours
from gpmsa.predictive.full import FullPrediction

if TYPE_CHECKING:
    from matplotlib.figure import Figure

BANDS = (("y", "new observation y", "0.8"), ("zeta", "eta + delta", "C1"),
         ("eta", "simulator eta", "C0"))  # fmt: skip
BAR_WIDTHS = {"y": 18.0, "zeta": 11.0, "eta": 5.0, "delta": 11.0}
"""Line widths (points) of the bands of a scalar output drawn at one value of x, as bars."""


def prediction_bands(
    pred: FullPrediction,
    observed=None,
    *,
    level: float = 0.9,
    max_panels: int = 6,
    x_column: int = 0,
    relative: bool = False,
) -> Figure:
    """Bands of a full prediction and the observations at its x: a Figure.

    A functional output gets one column per new x (at most ``max_panels``, evenly chosen): on
    top the central bands of probability ``level`` of a new observation y, of the real process
    eta + delta and of the simulator eta over the output grid (drawn in increasing order of the
    grid, whatever the order of ``pred.grid``), with the observed values; below,
    the discrepancy delta. A scalar output gets the same bands against the known input
    ``x_column`` (at a single value of x, bars of decreasing width about the mean's tick).
    With ``relative`` the top panels show everything minus the predicted mean of y, so that
    narrow bands on a large output (say 0.05 s on 4 s) can be seen.

    Over an output index of two columns (SEPIA's (time, angle) y_ind; ``pred.grid`` of shape
    (g, 2)) each column is a stack of maps over the points, each row on one colour scale: the
    predicted mean of y (linear on the points' triangles, a dot at each point; coloured markers
    where the points span no triangle), the width of its band of probability ``level``, the
    discrepancy's mean, and with ``observed`` the observed value minus the mean of y as
    coloured markers at the points. ``relative`` changes nothing there (the width and the
    observed minus the mean are relative already).

    Args:
        pred: a FullPrediction from ``full_prediction``.
        observed: (N, l) finite observed values at ``pred.x`` and ``pred.grid`` (e.g.
            held-out observations), or None.
        level: probability of the bands.
        max_panels: columns at most (functional output).
        x_column: the known input on the horizontal axis (scalar output), labelled with its
            name and unit as the emulator records them (``SimData(x_names=, x_units=)``).
        relative: subtract the predicted mean of y in the top panels.

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
        >>> data = gpmsa.SimData(x=x, t=t, y=x + t, x_names=["x"], t_names=["t"])
        >>> obs = gpmsa.ObsData(x=[[0.2], [0.5], [0.8]], y=[[0.7], [1.1], [1.3]])
        >>> emu = gpmsa.fit(data, obs, n_iter=50, tune=False, seed=0, discrepancy="constant")
        >>> pred = gpmsa.full_prediction(emu, obs, np.linspace(0.1, 0.9, 5)[:, None], seed=1)
        >>> fig = gpmsa.plots.prediction_bands(pred)
        >>> len(fig.axes)
        2
    """
    if not isinstance(pred, FullPrediction):
        raise GPMSAError(f"pred must be a FullPrediction, got {type(pred).__name__}")
    level = check_level(level)
    max_panels = check_count(max_panels, "max_panels")
    maps = is_map(pred.grid, "plots.prediction_bands")
    N, l = pred.x.shape[0], pred.grid.shape[0]
    if pred.x.shape[1] == 0 and l == 1:
        raise GPMSAError(
            "prediction_bands draws a scalar output against a known input, and this prediction "
            "has none (p = 0, no known inputs): read its bands with pred.interval(...) instead"
        )
    if pred.x.shape[1]:  # a functional output without known inputs draws no x axis
        x_column = check_count(x_column, "x_column", 0, pred.x.shape[1] - 1)
    if observed is not None:
        observed = _observed(observed, N, l)
    if not isinstance(relative, bool | np.bool_):
        raise GPMSAError(f"relative must be True or False, got {relative!r}")
    cols = np.unique(np.linspace(0, N - 1, min(max_panels, N)).round().astype(int))
    if maps:
        return _band_maps(pred, observed, cols, level)
    bands = {w: pred.interval(w, level) for w in ("y", "zeta", "eta", "delta")}
    eta_mean = pred.mean("eta")
    colour = dict(zip(("C0", "C1", "C2"), series_colours(3), strict=True))
    if relative:
        ref = pred.mean("y")
        bands.update({w: (bands[w][0] - ref, bands[w][1] - ref) for w in ("y", "zeta", "eta")})
        eta_mean = eta_mean - ref
        observed = None if observed is None else observed - ref
    ylabel = "output minus predicted mean of y" if relative else "output"
    pct = f"{100 * level:.0f} %"
    if l == 1:
        order = np.argsort(pred.x[:, x_column])
        xs = pred.x[order, x_column]
        fig = figure(6.0, 6.0)
        top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=[2, 1])
        bars = xs[0] == xs[-1]  # one x (or one repeated): a band there would be a hairline
        mean_style = {"marker": "_", "ms": BAR_WIDTHS["y"], "ls": "none"} if bars else {}
        for what, label, color in BANDS:
            lo, hi = bands[what]
            _band(top, xs, lo[order, 0], hi[order, 0], bars and BAR_WIDTHS[what],
                  color=colour.get(color, color), alpha=0.35, label=f"{label} ({pct})")  # fmt: skip
        top.plot(xs, eta_mean[order, 0], color=colour["C0"], lw=1, **mean_style)
        if observed is not None:
            top.plot(xs, observed[order, 0], "o", color=ink(), ms=3, label="observed")
        lo, hi = bands["delta"]
        _band(bottom, xs, lo[order, 0], hi[order, 0], bars and BAR_WIDTHS["delta"],
              color=colour["C2"], alpha=0.4)  # fmt: skip
        bottom.plot(xs, pred.mean("delta")[order, 0], color=colour["C2"], lw=1, **mean_style)
        bottom.axhline(0.0, color="0.6", lw=0.6)
        name, unit = _input(pred, x_column)
        bottom.set_xlabel(axis_label(name, unit))
        bottom.set_ylabel("discrepancy delta")
        top.set_ylabel(ylabel)
        top.legend(fontsize="small")
        return fig
    fig = figure(2.8 * cols.size + 0.6, 5.6)
    axes = fig.subplots(2, cols.size, squeeze=False, sharex=True, height_ratios=[2, 1])
    by_index = np.argsort(pred.grid, kind="stable")  # a grid may come in any order
    grid, delta_mean = pred.grid[by_index], pred.mean("delta")
    for c, i in enumerate(cols):
        top, bottom = axes[0, c], axes[1, c]
        for what, label, color in BANDS:
            lo, hi = bands[what]
            top.fill_between(grid, lo[i, by_index], hi[i, by_index], color=colour.get(color, color),
                             alpha=0.35, label=f"{label} ({pct})")  # fmt: skip
        top.plot(grid, eta_mean[i, by_index], color=colour["C0"], lw=1)
        if observed is not None:
            top.plot(grid, observed[i, by_index], "o", color=ink(), ms=3, label="observed")
        lo, hi = bands["delta"]
        bottom.fill_between(grid, lo[i, by_index], hi[i, by_index], color=colour["C2"], alpha=0.4)
        bottom.plot(grid, delta_mean[i, by_index], color=colour["C2"], lw=1)
        bottom.axhline(0.0, color="0.6", lw=0.6)
        bottom.set_xlabel(index_labels(pred.index_names, pred.index_units, pred.grid)[0])
        top.set_title(_inputs_text(pred, i), fontsize="small")
    axes[0, 0].set_ylabel(ylabel)
    axes[1, 0].set_ylabel("discrepancy delta")
    axes[0, 0].legend(fontsize="x-small")
    return fig


def _band(ax, xs: np.ndarray, lo: np.ndarray, hi: np.ndarray, bar: float, **style) -> None:
    """The band [lo, hi] along the increasing ``xs`` on ``ax``: filled between them, or, where
    ``bar`` (a line width in points) is given for a band at one value of x, a vertical bar that
    wide at it."""
    if bar:
        ax.vlines(xs, lo, hi, lw=bar, **style)
    else:
        ax.fill_between(xs, lo, hi, **style)


def _band_maps(pred: FullPrediction, observed, cols: np.ndarray, level: float):
    """One column of maps over the two-column ``pred.grid`` per new x in ``cols``: mean of y,
    width of its band, mean of delta, observed minus the mean of y; each row one scale."""
    lo, hi = pred.interval("y", level)
    y_mean, delta_mean = pred.mean("y"), pred.mean("delta")
    surface, markers = _maps.surface, _maps.markers
    labels = index_labels(pred.index_names, pred.index_units, pred.grid)
    rows = [
        (y_mean, _maps.value_norm(y_mean[cols], *([] if observed is None else [observed[cols]])),
         _maps.VALUES, "mean of y", surface),
        (hi - lo, _maps.value_norm(0.0, (hi - lo)[cols]), _maps.SPREAD,
         f"width of the {100 * level:.0f} % band of y", surface),
        (delta_mean, _maps.signed_norm(delta_mean[cols]), _maps.SIGNED, "mean of delta", surface),
    ]  # fmt: skip
    if observed is not None:
        rows.append((observed - y_mean, _maps.signed_norm((observed - y_mean)[cols]),
                     _maps.SIGNED, "observed minus mean of y", markers))  # fmt: skip
    fig = figure(2.9 * cols.size + 1.4, 2.5 * len(rows) + 0.4)
    axes = fig.subplots(len(rows), cols.size, squeeze=False, sharex=True, sharey=True)
    for r, (values, norm, cmap, label, draw) in enumerate(rows):
        for c, i in enumerate(cols):
            shade = draw(axes[r, c], pred.grid, values[i], norm, cmap, labels=labels)
            axes[r, c].set_title(label if r else f"{_inputs_text(pred, i)}\n{label}",
                                 fontsize="small")  # fmt: skip
        _maps.colour_bar(fig, shade, list(axes[r]), label)
    return fig


def _inputs_text(pred: FullPrediction, i: int) -> str:
    """The known inputs of the new x ``i`` as "name = value unit, ..." (or none)."""
    named = [(*_input(pred, k), v) for k, v in enumerate(pred.x[i])]
    xs = ", ".join(f"{n} = {v:.3g}{' ' + u if u else ''}" for n, u, v in named)
    return xs or "no known inputs"


def _input(pred: FullPrediction, k: int) -> tuple[str, str]:
    """(name, unit) of the known input ``k`` of ``pred`` ("x[k]" and "" where it records none)."""
    names, units = tuple(pred.x_names), tuple(pred.x_units)
    name = names[k] if k < len(names) else f"x[{k}]"
    return name, units[k] if k < len(units) else ""


def _observed(observed, N: int, l: int) -> np.ndarray:
    """``observed`` as (N, l) values at the prediction's x and grid; GPMSAError naming that
    shape otherwise, with advice for experiments on their own grids (an ObsData, a ragged
    list)."""
    want = f"observed must have shape ({N}, {l}) on pred.grid (one row per predicted x)"
    ragged = isinstance(observed, (list, tuple)) and len({np.size(e) for e in observed}) > 1
    if isinstance(observed, ObsData) or ragged:
        raise GPMSAError(
            f"{want}, got {type(observed).__name__} of experiments on their own grids: draw "
            "each with a prediction on its grid, full_prediction(emu, obs, obs.x[[j]], "
            "grid=obs.grids[j]), and observed=[obs.experiments[j]]"
        )
    observed = as_float(observed, "observed")
    if observed.ndim == 1 and l == 1:
        observed = observed[:, None]
    if observed.shape != (N, l):
        raise GPMSAError(f"{want}, got {observed.shape}")
    check_finite(observed, "observed")  # NaN or inf would be drawn as nothing, silently
    return observed
