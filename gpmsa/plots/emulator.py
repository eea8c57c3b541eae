"""The emulator's PC basis and weights, and its fit against held-out runs."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy.special import ndtri

from gpmsa.errors import GPMSAError
from gpmsa.fitting.emulator import Emulator
from gpmsa.model.basis import variance_shares
from gpmsa.model.data import (
    SimData,
    as_matrix,
    check_count,
    check_flag,
    check_level,
    column_order,
)
from gpmsa.plots import _maps
from gpmsa.plots._figure import axis_label, figure, index_labels, is_map, series_colours
from gpmsa.predictive.crossval import CrossValidation

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def pc_basis(emulator, *, max_pc: int = 6) -> Figure:
    """The basis vectors (native units, sd K_j over the output grid) and the runs' weights
    w_j against each input, one row per component (at most ``max_pc``): a Figure.

    The title of each basis panel gives the share of the standardised runs' variance the
    component carries. A scalar output (K = [[1]]) shows the weights only. Over an output index
    of two columns (l_sim, 2) (SEPIA's (time, angle) y_ind) each basis vector is a map over the
    points (linear on their triangles, a dot at each point) with its own colour bar, symmetric
    about zero.

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t, s = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1)), np.linspace(0, 1, 8)
        >>> data = gpmsa.SimData(x=x, t=t, y=np.outer(x, s) + np.outer(t, s**2), index=s)
        >>> emu = gpmsa.Emulator.from_params(data, {"betaU": [[1, 1], [1, 1]], "lamUz": [1, 1],
        ...                                         "lamWs": [1e3, 1e3], "lamWOs": [1e3]})
        >>> fig = gpmsa.plots.pc_basis(emu)
        >>> len(fig.axes)     # 2 components x (basis + 2 inputs)
        6
    """
    if not isinstance(emulator, Emulator):
        raise GPMSAError(f"emulator must be a gpmsa.Emulator, got {type(emulator).__name__}")
    std = emulator.standardizer
    maps = is_map(std.grid, "plots.pc_basis")
    p_u = min(emulator.p_u, check_count(max_pc, "max_pc"))
    scalar = emulator.l_sim == 1
    units = (*emulator.x_units, *emulator.t_units)
    inputs = [(n, emulator.x_unit[:, k] * (std.x_max[k] - std.x_min[k]) + std.x_min[k])
              for k, n in enumerate(emulator.x_names)]  # fmt: skip
    inputs += [(n, emulator.t_unit[:, k] * (std.t_max[k] - std.t_min[k]) + std.t_min[k])
               for k, n in enumerate(emulator.t_names)]  # fmt: skip
    inputs = [(axis_label(n, u), v) for (n, v), u in zip(inputs, units, strict=True)]
    y_std = std.y_to_std(emulator.y)
    total = float(np.sum(y_std**2))
    share = variance_shares(emulator.w, emulator.lam_sim, total) if total > 0 else None
    n_col = len(inputs) + (0 if scalar else 1)
    labels = index_labels(emulator.index_names, emulator.index_units, std.grid)
    fig = figure(2.6 * n_col + (1.2 if maps else 0.4), 2.2 * p_u + 0.4)
    axes = fig.subplots(p_u, n_col, squeeze=False)
    for j in range(p_u):
        row = list(axes[j])
        if not scalar:
            ax = row.pop(0)
            vector = std.y_sd * emulator.K[:, j]
            if maps:
                norm = _maps.signed_norm(vector)
                shade = _maps.surface(ax, std.grid, vector, norm, _maps.SIGNED, labels)
                _maps.colour_bar(fig, shade, ax, f"y_sd K{j + 1}")
            else:
                ax.plot(std.grid, vector, color=f"C{j}")
                ax.axhline(0.0, color="0.7", lw=0.6)
                ax.set_xlabel(labels[0])
            pct = f" ({100 * share[j]:.1f} % of variance)" if share is not None else ""
            ax.set_title(f"PC {j + 1}{pct}", fontsize="small")
        for ax, (name, values) in zip(row, inputs, strict=True):
            ax.plot(values, emulator.w[:, j], ".", ms=3, color=f"C{j}")
            ax.set_xlabel(name)
            if ax is row[0]:
                ax.set_ylabel(f"w{j + 1}")
    return fig


def _held_out_inputs(emulator, held_out: SimData) -> tuple[np.ndarray, np.ndarray]:
    """The held-out runs' x and t in the emulator's column order; GPMSAError when their outputs
    or output grid differ from the emulator's, or their named columns are not the emulator's
    (runs with the default names x0.., t0.. are read by position)."""
    if held_out.l_sim != emulator.l_sim:
        raise GPMSAError(f"held-out runs have {held_out.l_sim} outputs, the emulator "
                         f"{emulator.l_sim}")  # fmt: skip
    grid, index = emulator.standardizer.grid, held_out.index  # either may be None (scalar)
    if (
        grid is not None
        and index is not None
        and (np.shape(index) != np.shape(grid) or not np.allclose(index, grid))
    ):
        raise GPMSAError("held-out runs lie on another output grid (index) than the emulator's")
    columns = []
    sides = ((held_out.x, held_out.x_names, emulator.x_names, "x"),
             (held_out.t, held_out.t_names, emulator.t_names, "t"))  # fmt: skip
    for arr, names, mine, prefix in sides:
        default = tuple(f"{prefix}{i}" for i in range(len(names)))
        if tuple(names) == default or tuple(names) == tuple(mine):
            columns.append(arr)
        elif sorted(names) == sorted(mine):
            columns.append(arr[:, column_order(names, mine, f"held-out runs' {prefix}")])
        else:
            raise GPMSAError(f"held-out runs name their {prefix} columns {list(names)}, the "
                             f"emulator {list(mine)}")  # fmt: skip
    return columns[0], columns[1]


def _held_out_runs(emulator, held_out) -> tuple[np.ndarray | None, np.ndarray, np.ndarray]:
    """x, t (the emulator's column order) and y (n, l_sim) of held-out runs given as a SimData
    (`_held_out_inputs`) or as a tuple (x, t, y) of native arrays in the emulator's columns (any
    number of runs, one too: a SimData needs p + q + 2 of them); GPMSAError naming a bad part
    (``Emulator.predict`` checks x and t)."""
    if isinstance(held_out, SimData):
        return (*_held_out_inputs(emulator, held_out), held_out.y)
    if len(held_out) != 3:
        raise GPMSAError(f"held_out as a tuple must be (x, t, y), got {len(held_out)} items")
    x, t, y = held_out
    if x is None and emulator.p > 0:
        raise GPMSAError(
            f"held_out x is None, but the emulator has {emulator.p} known input(s) "
            f"{list(emulator.x_names)}: give their values (runs x {emulator.p}) as the tuple's "
            "first item (None only for an emulator without known inputs)"
        )
    y = as_matrix(y, "held_out y", ncols=emulator.l_sim)
    rows = {"t": as_matrix(t, "held_out t", ncols=emulator.q).shape[0]}
    if x is not None:
        rows["x"] = as_matrix(x, "held_out x", ncols=emulator.p, no_columns=True).shape[0]
    if any(n != y.shape[0] for n in rows.values()):
        raise GPMSAError(f"held_out x, t and y must have one row per run: y has {y.shape[0]} "
                         f"rows, {', '.join(f'{k} {v}' for k, v in rows.items())}")  # fmt: skip
    return x, t, y


def emulator_fit(emulator, held_out, *, level: float = 0.9, max_runs: int = 6,
                 draws: bool = True, n_draws: int | None = 100) -> Figure:  # fmt: skip
    """Emulator predictions against held-out runs (or a cross-validation): a Figure.

    Left: predicted mean against the run's value for every output element, with central
    intervals of probability ``level``, and the share of values they cover. Right (a functional
    output): up to ``max_runs`` runs over the output grid, their value and the predicted band.
    Over an output index of two columns (l_sim, 2) (SEPIA's (time, angle) y_ind), one row of
    maps per run instead: the predicted mean (linear on the points' triangles, a dot at each
    point), the width of its interval, and the run's value minus the mean as coloured markers
    at the points; each column on one colour scale.

    Args:
        emulator: the gpmsa.Emulator.
        held_out: a SimData of runs not used in the fit (predicted by ``Emulator.predict``, over
            the retained draws when ``draws``), or their arrays ``(x, t, y)`` in native units
            and the emulator's columns (x None without known inputs; any number of runs, where
            a SimData needs p + q + 2), or a CrossValidation from ``cross_validate``.
        level: probability of the intervals.
        max_runs: runs drawn on the right.
        draws: average the prediction of held-out runs over the posterior draws (at most
            ``n_draws`` of them, evenly spaced; None: all).

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
        >>> data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t, x_names=["x"], t_names=["t"])
        >>> emu = gpmsa.Emulator.from_params(data, {"betaU": [[2], [1]], "lamUz": [1],
        ...                                         "lamWs": [1e4], "lamWOs": [1e4]})
        >>> fig = gpmsa.plots.emulator_fit(emu, gpmsa.cross_validate(emu, draws=False))
        >>> len(fig.axes)
        1
    """
    level = check_level(level)
    draws = check_flag(draws, "draws")
    if n_draws is not None:
        check_count(n_draws, "n_draws")
    maps = is_map(emulator.standardizer.grid, "plots.emulator_fit")
    if isinstance(held_out, CrossValidation):
        mean, var, actual = held_out.mean, held_out.var, held_out.y
        what = "cross-validation"
        if held_out.y.shape != emulator.y.shape or not np.allclose(held_out.y, emulator.y):
            raise GPMSAError(
                "held_out is the cross-validation of another emulator (its runs' outputs differ "
                "from this emulator's)"
            )
    elif isinstance(held_out, SimData | tuple):
        x, t, actual = _held_out_runs(emulator, held_out)
        use = draws and emulator.n_draws > 0
        mean, var = emulator.predict(x, t, draws=use, n_draws=n_draws)
        what = f"{actual.shape[0]} held-out run{'' if actual.shape[0] == 1 else 's'}"
    else:
        raise GPMSAError(
            f"held_out must be a SimData of held-out runs, their (x, t, y) arrays or a "
            f"CrossValidation, got {type(held_out).__name__}"
        )
    half = ndtri(0.5 + level / 2) * np.sqrt(var)
    inside = float(np.mean(np.abs(actual - mean) <= half))
    title = f"{what}: {100 * inside:.0f} % inside the {100 * level:.0f} % intervals"
    functional = actual.shape[1] > 1
    if functional:
        n_rows = min(check_count(max_runs, "max_runs"), actual.shape[0])
        rows = np.unique(np.linspace(0, actual.shape[0] - 1, n_rows)
                         .round().astype(int))  # fmt: skip
    if functional and maps:
        return _fit_maps(emulator, rows, actual, mean, half, level, title)
    fig = figure(10.0 if functional else 5.0, 4.2)
    axes = fig.subplots(1, 2 if functional else 1, squeeze=False)[0]
    _fit_scatter(axes[0], actual, mean, half, title)
    if functional:
        grid = emulator.standardizer.grid
        colours = series_colours(min(rows.size, 10))
        for c, i in enumerate(rows):
            col = colours[c % 10]
            axes[1].fill_between(grid, mean[i] - half[i], mean[i] + half[i], color=col, alpha=0.2)
            axes[1].plot(grid, mean[i], color=col, lw=1)
            axes[1].plot(grid, actual[i], "o", color=col, ms=3)
        axes[1].set_xlabel(index_labels(emulator.index_names, emulator.index_units, grid)[0])
        axes[1].set_ylabel("output")
        axes[1].set_title("runs (dots) and predicted bands", fontsize="small")
    return fig


def _fit_scatter(ax, actual: np.ndarray, mean: np.ndarray, half: np.ndarray, title: str) -> None:
    """Predicted mean against the runs' values, every output element, with its interval."""
    ax.errorbar(actual.ravel(), mean.ravel(), yerr=half.ravel(), fmt=".", ms=3, lw=0.6,
                color="C0", ecolor="0.6")  # fmt: skip
    lims = [min(actual.min(), mean.min()), max(actual.max(), mean.max())]
    ax.plot(lims, lims, color="C3", lw=1)
    ax.set_xlabel("run value")
    ax.set_ylabel("predicted")
    ax.set_title(title, fontsize="small")


def _fit_maps(emulator, rows, actual, mean, half, level: float, title: str):
    """The scatter of ``_fit_scatter`` (left) and per run in ``rows`` a row of maps over the
    emulator's two-column index: predicted mean, interval width, run minus mean."""
    points = emulator.standardizer.grid
    labels = index_labels(emulator.index_names, emulator.index_units, points)
    fig = figure(12.5, max(4.2, 2.5 * rows.size + 0.6))
    panels = fig.add_gridspec(rows.size, 4, width_ratios=[1.4, 1, 1, 1])
    _fit_scatter(fig.add_subplot(panels[:, 0]), actual, mean, half, title)
    surface, markers = _maps.surface, _maps.markers
    columns = (
        (mean, _maps.value_norm(mean[rows], actual[rows]), _maps.VALUES, "predicted mean",
         surface),
        (2 * half, _maps.value_norm(0.0, 2 * half[rows]), _maps.SPREAD,
         f"width of the {100 * level:.0f} % interval", surface),
        (actual - mean, _maps.signed_norm(actual[rows] - mean[rows]), _maps.SIGNED,
         "run minus predicted mean", markers),
    )  # fmt: skip
    for c, (values, norm, cmap, label, draw) in enumerate(columns, start=1):
        axes = [fig.add_subplot(panels[r, c]) for r in range(rows.size)]
        for ax, i in zip(axes, rows, strict=True):
            shade = draw(ax, points, values[i], norm, cmap, labels=labels)
            ax.set_title(f"run {i}: {label}", fontsize="small")
        _maps.colour_bar(fig, shade, axes, label)
    return fig
