"""Bars of Sobol main and total effects (and, for a functional output, along its grid), and the
main-effect functions with their band over draws."""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

import numpy as np
from scipy.stats import norm

from gpmsa.errors import GPMSAError
from gpmsa.model.data import check_count, check_level
from gpmsa.plots import _maps
from gpmsa.plots._figure import (
    axis_label,
    figure,
    index_columns,
    index_labels,
    ink,
    is_map,
    series_colours,
)
from gpmsa.predictive.sobol import Sensitivity

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def sensitivity_bars(sens: Sensitivity, *, level: float = 0.9) -> Figure:
    """Main- and total-effect indices per input with their spread over posterior draws.

    Left: bars of the aggregated indices (mean over draws) with the central interval of
    probability ``level`` over draws as error bars (the interval itself: a skewed spread over
    draws can leave the mean outside it). Right (a functional output): main (solid)
    and total (dashed) effect of each input along the output grid, with their bands. Over an
    output index of two columns (l_sim, 2) (SEPIA's (time, angle) y_ind), maps of each input's
    main (top row) and total (bottom row) effect over the points instead, the mean over draws
    (linear on the points' triangles, a dot at each point; blank where the output does not
    vary), all on one colour scale from 0 to 1.

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
        >>> data = gpmsa.SimData(x=x, t=t, y=x + 0.3 * t, x_names=["x"], t_names=["t"])
        >>> emu = gpmsa.Emulator.from_params(data, {"betaU": [[1], [1]], "lamUz": [1],
        ...                                         "lamWs": [1e4], "lamWOs": [1e4]})
        >>> fig = gpmsa.plots.sensitivity_bars(gpmsa.sensitivity(emu, draws=False))
        >>> len(fig.axes)
        1
    """
    if not isinstance(sens, Sensitivity):
        raise GPMSAError(f"sens must be a Sensitivity, got {type(sens).__name__}")
    level = check_level(level)
    q = [(1 - level) / 2, (1 + level) / 2]
    maps = is_map(sens.grid, "plots.sensitivity_bars")
    functional = sens.grid.shape[0] > 1
    d = len(sens.names)
    if maps:
        fig = figure(5.5 + 2.8 * d + 0.8, 5.6)
        panels = fig.add_gridspec(2, 1 + d, width_ratios=[5.5 / 2.8] + [1] * d)
        axes = [fig.add_subplot(panels[:, 0])]
    else:
        fig = figure(11.0 if functional else 5.5, 4.0)
        axes = fig.subplots(1, 2 if functional else 1, squeeze=False)[0]
    pos = np.arange(d)
    main_colour, total_colour = series_colours(2)
    for off, kind, arr, color in ((-0.2, "main", sens.main_aggregated, main_colour),
                                  (0.2, "total", sens.total_aggregated, total_colour)):  # fmt: skip
        lo, hi = np.quantile(arr, q, axis=0)
        axes[0].bar(pos + off, arr.mean(axis=0), width=0.4, color=color, label=f"{kind} effect")
        # the interval [lo, hi] itself: a skewed spread can leave the mean outside it
        axes[0].errorbar(pos + off, (lo + hi) / 2, yerr=(hi - lo) / 2, fmt="none", ecolor=ink(),
                         capsize=3)  # fmt: skip
    axes[0].set_xticks(pos, sens.names)
    axes[0].set_ylim(0.0, 1.05)
    axes[0].set_ylabel("Sobol index")
    title = "aggregated over the output grid" if functional else "Sobol indices"
    spread = (" (the point estimate)" if list(np.ravel(sens.draw_index)) == [-1]
              else f"; bars: {100 * level:.0f} % over {sens.main.shape[0]} draws")  # fmt: skip
    axes[0].set_title(title + spread, fontsize="small")
    axes[0].legend(fontsize="small")
    if maps:
        _effect_maps(fig, panels, sens)
    elif functional:
        ax = axes[1]
        with warnings.catch_warnings():  # all-NaN grid points (zero output variance)
            warnings.simplefilter("ignore", RuntimeWarning)
            colours = series_colours(len(sens.names))
            for k, name in enumerate(sens.names):
                for arr, style in ((sens.main, "-"), (sens.total, "--")):
                    col = arr[:, :, k]
                    ax.plot(sens.grid, np.nanmean(col, axis=0), style, color=colours[k],
                            label=name if style == "-" else None)  # fmt: skip
                    if col.shape[0] > 1:
                        lo, hi = np.nanquantile(col, q, axis=0)
                        ax.fill_between(sens.grid, lo, hi, color=colours[k], alpha=0.15)
        ax.set_ylim(0.0, 1.05)
        ax.set_xlabel(index_labels(sens.index_names, sens.index_units, sens.grid)[0])
        ax.set_ylabel("index (solid: main, dashed: total)")
        ax.legend(fontsize="small")
    return fig


def _effect_maps(fig, panels, sens: Sensitivity) -> None:
    """Each input's main (row 0) and total (row 1) effect over the two-column ``sens.grid``,
    the mean over draws, in columns 1.. of the gridspec ``panels``; one scale, 0 to 1."""
    norm = _maps.value_norm(0.0, 1.0)
    labels = index_labels(sens.index_names, sens.index_units, sens.grid)
    axes = []
    with warnings.catch_warnings():  # all-NaN grid points (zero output variance)
        warnings.simplefilter("ignore", RuntimeWarning)
        for r, (arr, kind) in enumerate(((sens.main, "main"), (sens.total, "total"))):
            for k, name in enumerate(sens.names):
                ax = fig.add_subplot(panels[r, 1 + k])
                shade = _maps.surface(ax, sens.grid, np.nanmean(arr[:, :, k], axis=0), norm,
                                      _maps.VALUES, labels)  # fmt: skip
                ax.set_title(f"{kind} effect of {name}", fontsize="small")
                axes.append(ax)
    _maps.colour_bar(fig, shade, axes, "Sobol index (mean over draws)")


def main_effect_curves(
    sens: Sensitivity, *, level: float = 0.9, output: int = 0, level_names: dict | None = None
) -> Figure:
    """Main-effect functions E[y | z_k] of each varied input, with their band over draws.

    One panel per varied input (SEPIA's main-effect plot), on a shared output axis: the mean
    over posterior draws of ``sens.main_effect`` against the input's grid, the central interval
    of probability ``level`` over the draws as a band (none for the point estimate), and the
    output's mean over the box as a dotted line. Axes read "name (unit)". With the GP's own
    variance about the curves (``sensitivity(..., effect_variance=True)``; SEPIA's ``mef_v``) a
    wider, lighter band: the mean -+ the normal quantile of ``level`` times the mixture's sd
    over draws (the mean GP variance plus the variance of the curves over draws), the GP's
    uncertainty about the function between the runs as well as the parameters'.

    A categorical input (``sens.categorical``) has no values between its levels: its panel
    shows points at the levels, the same intervals as error bars (the wider, lighter one with
    the GP's variance), and the levels as the axis's ticks (their names from ``level_names``).

    Args:
        sens: a Sensitivity from ``gpmsa.sensitivity(..., main_effect_grid=G)``.
        level: probability of the bands.
        output: the output element (index on the simulation grid) of a functional output.
        level_names: categorical input name -> the names of its levels for the tick labels:
            a dict level code -> name, or a list of names, one per level varied over in
            increasing order (default: the integer codes).

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
        >>> data = gpmsa.SimData(x=x, t=t, y=x + 0.3 * t, x_names=["x"], t_names=["t"],
        ...                      x_units=["m"])
        >>> emu = gpmsa.Emulator.from_params(data, {"betaU": [[1], [1]], "lamUz": [1],
        ...                                         "lamWs": [1e4], "lamWOs": [1e4]})
        >>> sens = gpmsa.sensitivity(emu, draws=False, main_effect_grid=11)
        >>> fig = gpmsa.plots.main_effect_curves(sens)
        >>> [ax.get_xlabel() for ax in fig.axes]
        ['x (m)', 't']
    """
    if not isinstance(sens, Sensitivity):
        raise GPMSAError(f"sens must be a Sensitivity, got {type(sens).__name__}")
    if sens.main_effect is None:
        raise GPMSAError("sens has no main-effect functions: compute them with "
                         "gpmsa.sensitivity(..., main_effect_grid=G)")  # fmt: skip
    level = check_level(level)
    l_sim = sens.main_effect.shape[2]
    output = check_count(output, "output", 0, l_sim - 1)
    q = [(1 - level) / 2, (1 + level) / 2]
    d = len(sens.names)
    cols = min(d, 4)
    rows = -(-d // cols)
    fig = figure(3.2 * cols, 2.8 * rows)
    axes = fig.subplots(rows, cols, squeeze=False, sharey=True).ravel()
    curves = sens.main_effect[:, :, output, :]  # (S, G, d)
    spread = curves.shape[0] > 1
    gp = None if sens.main_effect_variance is None else sens.main_effect_variance[:, :, output, :]
    z = float(norm.ppf((1 + level) / 2))
    y_name = sens.y_names[output] if output < len(sens.y_names) else "y"
    y_unit = sens.y_units[output] if output < len(sens.y_units) else ""
    ticks = _level_ticks(sens, level_names)
    for k, name in enumerate(sens.names):
        ax, grid, cur = axes[k], sens.effect_grid[:, k], curves[:, :, k]
        if name in ticks:
            _level_points(ax, grid, cur, None if gp is None else gp[:, :, k], q, z, level, spread)
            ax.set_xticks(*ticks[name])
            ax.margins(x=0.15)
            ax.axhline(float(np.mean(sens.mean[:, output])), color="0.5", ls=":", lw=1)
            ax.set_xlabel(axis_label(name, sens.units.get(name, "")))
            continue
        ax.plot(grid, cur.mean(axis=0), color="C0", label="mean over draws" if spread else None)
        if gp is not None:
            sd = np.sqrt(gp[:, :, k].mean(axis=0) + np.var(cur, axis=0))
            ax.fill_between(grid, cur.mean(axis=0) - z * sd, cur.mean(axis=0) + z * sd,
                            color="C0", alpha=0.12,
                            label=f"{100 * level:.0f} % with the GP's variance")  # fmt: skip
        if spread:
            lo, hi = np.quantile(cur, q, axis=0)
            ax.fill_between(grid, lo, hi, color="C0", alpha=0.25,
                            label=f"{100 * level:.0f} % over draws")  # fmt: skip
        ax.axhline(float(np.mean(sens.mean[:, output])), color="0.5", ls=":", lw=1)
        ax.set_xlabel(axis_label(name, sens.units.get(name, "")))
    axes[0].set_ylabel(axis_label(f"E[{y_name} | input]", y_unit))
    for ax in axes[d:]:
        ax.set_visible(False)
    if spread or gp is not None:
        axes[0].legend(fontsize="small")
    where = f" at output {output}{_point_title(sens, output)}" if l_sim > 1 else ""
    drawn = f"over {curves.shape[0]} draws" if spread else "the point estimate"
    fig.suptitle(f"main effects{where} ({drawn})", fontsize="small")
    return fig


def _point_title(sens: Sensitivity, output: int) -> str:
    """Where output element ``output`` lies on the output index, for a title: ", time = 0.6 s,
    angle = 0 rad" (the index's names and units; "output index" or "output index[:, k]" where
    none were given); "" without an index."""
    grid = getattr(sens, "grid", None)
    if grid is None or np.shape(grid)[0] != sens.main_effect.shape[2]:
        return ""
    columns = index_columns(sens.index_names, sens.index_units, grid)
    row = np.reshape(grid[output], -1)
    parts = [f"{n} = {float(v):.4g}" + (f" {u}" if u else "")
             for (n, u), v in zip(columns, row, strict=True)]  # fmt: skip
    return ", " + ", ".join(parts)


def _level_ticks(sens: Sensitivity, level_names) -> dict[str, tuple[list[float], list[str]]]:
    """Per categorical input of ``sens``: its levels and their tick labels (``level_names``'
    names, or the integer codes); GPMSAError naming the input for a bad ``level_names``."""
    if level_names is None:
        level_names = {}
    if not isinstance(level_names, dict):
        raise GPMSAError(f"level_names must be None or a dict input name -> level names, got "
                         f"{level_names!r}")  # fmt: skip
    for name in level_names:
        if name not in sens.categorical:
            raise GPMSAError(f"level_names names {name!r}, not a varied categorical input; those "
                             f"are {sens.categorical}")  # fmt: skip
    out = {}
    for name in sens.categorical:
        levels = [int(v) for v in sens.bounds[name]]
        given = level_names.get(name)
        if given is None:
            labels = [str(v) for v in levels]
        elif isinstance(given, dict):
            missing = [v for v in levels if v not in given]
            extra = [v for v in given if v not in levels]
            if missing:
                also = f"; {extra} are not among them" if extra else ""
                raise GPMSAError(f"level_names[{name!r}] has no name for levels {missing} (the "
                                 f"levels varied over: {levels}{also})")  # fmt: skip
            labels = [str(given[v]) for v in levels]
        elif isinstance(given, list | tuple) and len(given) == len(levels):
            labels = [str(v) for v in given]
        else:
            raise GPMSAError(f"level_names[{name!r}] must be a dict level -> name or a list of "
                             f"{len(levels)} names (one per level of {levels}), got "
                             f"{given!r}")  # fmt: skip
        out[name] = ([float(v) for v in levels], labels)
    return out


def _level_points(ax, grid, cur, gp, q, z: float, level: float, spread: bool) -> None:
    """A categorical input's main effect on ``ax``: the mean over draws at each level (the
    grid's finite rows) as points, the interval over draws and (``gp``: the GP's variance
    per draw) the wider one with it as error bars; nothing drawn between the levels."""
    at = np.isfinite(grid)
    grid, cur = grid[at], cur[:, at]
    mean = cur.mean(axis=0)
    if gp is not None:
        sd = np.sqrt(gp[:, at].mean(axis=0) + np.var(cur, axis=0))
        ax.errorbar(grid, mean, yerr=z * sd, fmt="none", ecolor="C0", alpha=0.4, elinewidth=6,
                    label=f"{100 * level:.0f} % with the GP's variance")  # fmt: skip
    if spread:
        lo, hi = np.quantile(cur, q, axis=0)
        # the interval [lo, hi] itself: a skewed spread can leave the mean outside it
        ax.errorbar(grid, (lo + hi) / 2, yerr=(hi - lo) / 2, fmt="none", ecolor="C0",
                    capsize=4, label=f"{100 * level:.0f} % over draws")  # fmt: skip
    ax.plot(grid, mean, "o", color="C0", label="mean over draws" if spread else None)
