"""The observations projected onto the emulator's basis, against the simulation runs: per
component (``obs_projection``) and in pairs of components (``weight_pairs``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from gpmsa.calibration.observations import check_emulator, reduce
from gpmsa.errors import GPMSAError
from gpmsa.mcmc.diagnostics import histogram_bins
from gpmsa.model.data import ObsData, check_count
from gpmsa.plots import _maps
from gpmsa.plots._figure import check_bins, figure, index_labels, is_map, series_colours

if TYPE_CHECKING:
    from matplotlib.figure import Figure

MAP_EXPERIMENTS = 3
"""Experiments whose residual a two-column index's last row maps, at most."""


def obs_projection(emulator, obs: ObsData, *, max_pc: int = 6, bins: int = 30) -> Figure:
    """Can the emulator reach the observations? Per basis component (at most ``max_pc``): a
    histogram of the runs' weights w_j with each experiment's weight u_j (its GLS projection,
    as calibration reduces it) as a vertical line, the title counting the experiments outside
    the runs' range; for a functional output a last panel of what the basis misses (native
    units over the output grid): the runs' residuals y - mean - sd K w in grey, each
    experiment's in colour. SEPIA's ``plot_K_weights``, ``plot_u_w_pairs`` (diagonal) and
    ``plot_K_residuals`` in one Figure. No discrepancy basis: the weights shown are those a
    calibration without one fits. Over an output index of two columns (l_sim, 2) (SEPIA's
    (time, angle) y_ind) the last row holds maps: the runs' rms residual at each point (linear
    on the points' triangles, a dot at each point), and the first 3 experiments' residuals as
    coloured markers at their own points, on one colour scale symmetric about zero.

    Args:
        emulator: a gpmsa.Emulator.
        obs: a gpmsa.ObsData (experiments on the simulation grid or their own index; known
            inputs up to calibration's extrapolation margin outside the runs' range are shown,
            with its warning).
        max_pc: components shown at most.
        bins: histogram bins.

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t, s = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1)), np.linspace(0, 1, 8)
        >>> data = gpmsa.SimData(x=x, t=t, y=np.outer(x, s) + np.outer(t, s**2), index=s)
        >>> emu = gpmsa.Emulator.from_params(data, {"betaU": [[1, 1], [1, 1]], "lamUz": [1, 1],
        ...                                         "lamWs": [1e3, 1e3], "lamWOs": [1e3]})
        >>> obs = gpmsa.ObsData(x=[[0.5], [0.5]], y=[0.5 * s + 0.5 * s**2, 0.5 * s + 3 * s**2])
        >>> fig = gpmsa.plots.obs_projection(emu, obs)    # the second: t = 3, beyond the runs
        >>> [ax.get_title() for ax in fig.axes[:2]]
        ['PC 1: 1 of 2 outside the runs', 'PC 2: 1 of 2 outside the runs']
    """
    check_emulator(emulator, categorical_theta=True)  # theta plays no part here
    if not isinstance(obs, ObsData):
        raise GPMSAError(f"obs must be a gpmsa.ObsData, got {type(obs).__name__}")
    max_pc = check_count(max_pc, "max_pc")
    maps = is_map(emulator.standardizer.grid, "plots.obs_projection")
    reduced = reduce(emulator, obs, None, extrapolate=True).obs  # a plot shows them all
    n_pc = min(max_pc, emulator.p_u)
    functional = emulator.K.shape[0] > 1
    bins = check_bins(bins, n_pc, "plots.obs_projection")
    n_cols = min(3, n_pc)
    n_rows = -(-n_pc // n_cols)
    width = 3.2 * n_cols + 0.4
    if maps:  # room for the runs' map, the experiments' and two colour bars
        width = max(width, 3.0 * (1 + min(obs.n, MAP_EXPERIMENTS)) + 1.6)
    fig = figure(width, 2.4 * (n_rows + functional) + 0.4)
    grid = fig.add_gridspec(n_rows + functional, n_cols)
    for j in range(n_pc):
        ax = fig.add_subplot(grid[j // n_cols, j % n_cols])
        w, u = emulator.w[:, j], reduced.u[:, j]
        ax.hist(w, bins=histogram_bins(w, bins), color="0.7", label="runs")
        colours = series_colours(min(u.size, 10))
        for e, value in enumerate(u):
            ax.axvline(
                value, color=colours[e % 10], lw=1.2, label=f"experiment {e}" if e < 10 else None
            )
        outside = int(np.sum((u < w.min()) | (u > w.max())))
        ax.set_title(f"PC {j + 1}: {outside} of {u.size} outside the runs", fontsize="medium")
        ax.set_xlabel(f"weight w{j + 1}")
    fig.axes[0].legend(fontsize="small", loc="upper right")
    if functional and maps:
        _residual_maps(fig, grid[n_rows, :], emulator, obs, reduced)
    elif functional:
        _residuals(fig.add_subplot(grid[n_rows, :]), emulator, obs, reduced)
    return fig


def weight_pairs(
    emulator, obs: ObsData | None = None, *, max_pc: int = 4, bins: int = 20
) -> Figure:
    """The runs' weights in pairs of basis components (SEPIA's ``plot_u_w_pairs``): below the
    diagonal, w_j against w_i of every run (grey) with each experiment's u (its GLS
    projection, as calibration without a discrepancy reduces it) in colour, the title counting
    the experiments outside the runs' convex hull in that plane (inside every range, an
    experiment can still lie where no run went); on the diagonal, each component's histogram.
    At most ``max_pc`` components: a Figure.

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t, s = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1)), np.linspace(0, 1, 8)
        >>> data = gpmsa.SimData(x=x, t=t, y=np.outer(x, s) + np.outer(t, s**2), index=s)
        >>> emu = gpmsa.Emulator.from_params(data, {"betaU": [[1, 1], [1, 1]], "lamUz": [1, 1],
        ...                                         "lamWs": [1e3, 1e3], "lamWOs": [1e3]})
        >>> obs = gpmsa.ObsData(x=[[0.5], [0.5]], y=[0.5 * s + 0.5 * s**2, 0.5 * s + 3 * s**2])
        >>> fig = gpmsa.plots.weight_pairs(emu, obs)
        >>> fig.axes[2].get_title()     # w2 against w1
        '1 of 2 outside the runs'
    """
    from matplotlib.lines import Line2D

    check_emulator(emulator, categorical_theta=True)  # theta plays no part here
    if obs is not None and not isinstance(obs, ObsData):
        raise GPMSAError(f"obs must be a gpmsa.ObsData or None, got {type(obs).__name__}")
    n_pc = min(check_count(max_pc, "max_pc"), emulator.p_u)
    bins = check_bins(bins, n_pc, "plots.weight_pairs")
    u = None if obs is None else reduce(emulator, obs, None, extrapolate=True).obs.u
    colours = series_colours(0 if u is None else min(u.shape[0], 10))
    w = emulator.w
    fig = figure(2.2 * n_pc + 0.6, 2.2 * n_pc + 0.4)
    axes = fig.subplots(n_pc, n_pc, squeeze=False)
    for i in range(n_pc):
        for j in range(n_pc):
            ax = axes[i, j]
            if j > i:
                ax.set_axis_off()
                continue
            if i == j:
                ax.hist(w[:, i], bins=histogram_bins(w[:, i], bins), color="0.7")
            else:
                ax.plot(w[:, j], w[:, i], ".", ms=3, color="0.6")
                if u is not None:
                    for e in range(u.shape[0]):
                        ax.plot(u[e, j], u[e, i], "o", ms=5, color=colours[e % 10])
                    outside = _outside_hull(w[:, [j, i]], u[:, [j, i]])
                    if outside is not None:
                        ax.set_title(f"{outside} of {u.shape[0]} outside the runs",
                                     fontsize="small")  # fmt: skip
            if i == n_pc - 1:
                ax.set_xlabel(f"w{j + 1}")
            if j == 0 and i > 0:
                ax.set_ylabel(f"w{i + 1}")
    if u is not None and n_pc > 1:  # the experiments' colours, in the empty upper corner
        handles = [Line2D([], [], ls="", marker=".", color="0.6", label="runs")]
        handles += [Line2D([], [], ls="", marker="o", color=colours[e], label=f"experiment {e}")
                    for e in range(min(u.shape[0], 10))]  # fmt: skip
        axes[0, n_pc - 1].legend(handles=handles, fontsize="small", loc="upper right")
    return fig


def _outside_hull(runs: np.ndarray, points: np.ndarray) -> int | None:
    """How many of ``points`` (k, 2) lie outside the convex hull of ``runs`` (m, 2); None where
    the runs span no area (collinear)."""
    from scipy.spatial import Delaunay, QhullError

    try:
        hull = Delaunay(runs)
    except QhullError:
        return None
    return int(np.sum(hull.find_simplex(points) < 0))


def _misses(emulator, obs: ObsData, reduced) -> tuple[np.ndarray, list[np.ndarray]]:
    """What the basis misses, native units: of the runs (m, l_sim), of each experiment (l_j,)."""
    std = emulator.standardizer
    fitted = (
        emulator.w @ emulator.K.T * std.y_sd
        if std.columnwise
        else std.y_sd * emulator.w @ emulator.K.T
    )
    runs = (emulator.y - std.y_mean) - fitted
    grids = obs.output_grids(emulator.index_names)
    misses = [std.sd_on(grids[e]) * (y_std - K @ u)
              for e, (y_std, K, u) in enumerate(zip(reduced.y_std, reduced.K, reduced.u,
                                                    strict=True))]  # fmt: skip
    return runs, misses


def _residuals(ax, emulator, obs: ObsData, reduced) -> None:
    """What the basis misses of the runs (grey) and of each experiment (colour), native units."""
    std = emulator.standardizer
    runs, misses = _misses(emulator, obs, reduced)
    ax.plot(std.grid, runs.T, color="0.75", lw=0.6)
    grids = obs.output_grids(emulator.index_names)
    colours = series_colours(min(len(misses), 10))
    for e, miss in enumerate(misses):
        grid = std.grid if grids[e] is None else grids[e]
        ax.plot(grid, miss, color=colours[e % 10], lw=1.2)
    rms_runs = float(np.sqrt(np.mean(runs**2)))
    rms_obs = float(np.sqrt(np.mean(np.concatenate(misses) ** 2)))
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.set_title(
        f"beyond {emulator.p_u} components: rms {rms_runs:.3g} (runs), {rms_obs:.3g} (experiments)",
        fontsize="medium",
    )
    ax.set_xlabel(index_labels(emulator.index_names, emulator.index_units, std.grid)[0])
    ax.set_ylabel("residual")


def _residual_maps(fig, cell, emulator, obs: ObsData, reduced) -> None:
    """What the basis misses over a two-column index, in the gridspec ``cell``: the runs' rms
    at each point, and the first experiments' residuals at their points."""
    std = emulator.standardizer
    labels = index_labels(emulator.index_names, emulator.index_units, std.grid)
    runs, misses = _misses(emulator, obs, reduced)
    shown = misses[:MAP_EXPERIMENTS]
    panels = cell.subgridspec(1, 1 + len(shown))
    ax = fig.add_subplot(panels[0, 0])
    rms = np.sqrt(np.mean(runs**2, axis=0))
    shade = _maps.surface(ax, std.grid, rms, _maps.value_norm(0.0, rms), _maps.SPREAD, labels)
    _maps.colour_bar(fig, shade, ax, "rms residual")
    ax.set_title(f"runs beyond {emulator.p_u} components: rms {np.sqrt(np.mean(runs**2)):.3g}",
                 fontsize="small")  # fmt: skip
    norm = _maps.signed_norm(*shown)
    axes = []
    grids = obs.output_grids(emulator.index_names)
    for e, miss in enumerate(shown):
        ax = fig.add_subplot(panels[0, 1 + e])
        grid = std.grid if grids[e] is None else grids[e]
        dots = _maps.markers(ax, grid, miss, norm, _maps.SIGNED, background=std.grid,
                             labels=labels)  # fmt: skip
        ax.set_title(f"experiment {e}: rms {np.sqrt(np.mean(miss**2)):.3g}", fontsize="small")
        axes.append(ax)
    _maps.colour_bar(fig, dots, axes, "residual")
