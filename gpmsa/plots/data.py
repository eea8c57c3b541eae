"""The simulation runs and the observations before any fit (SEPIA's ``plot_data``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from gpmsa.errors import GPMSAError
from gpmsa.model.data import ObsData, SimData
from gpmsa.plots import _maps
from gpmsa.plots._figure import axis_label, figure, index_labels, ink, is_map

if TYPE_CHECKING:
    from matplotlib.figure import Figure

MAP_PANELS = 4
"""Runs, and experiments, drawn at most as maps over a two-column output index."""


def data(sim: SimData, obs: ObsData | None = None, *, color_by: str | None = None) -> Figure:
    """The runs' outputs and the observations in native units, a first look before fitting (as
    SEPIA's ``plot_data``): a Figure.

    A functional output (l_sim > 1): every run over the output grid, coloured by the input
    ``color_by`` (a name of ``sim``'s x or t inputs, checked for a scalar output too; default
    its first calibration parameter) with a colour bar, and every experiment over its own grid
    in black. Over an output index of two columns (l_sim, 2) (SEPIA's (time, angle) y_ind),
    maps on one colour scale: a row of 4 runs at evenly spaced ranks of ``color_by`` (the
    lowest to the highest), each coloured linearly on the points' triangles with a dot at each
    point, and a row of the first 4 experiments, their values as coloured markers at their own
    points over the simulation points' grey dots. A scalar output: the output against each
    input, one panel each; an experiment at its known inputs in the x panels, and as a
    horizontal line in the t panels (where the runs cross it, theta may lie).

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t, s = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1)), np.linspace(0, 1, 8)
        >>> sim = gpmsa.SimData(x=x, t=t, y=np.outer(x, s) + np.outer(t, s**2), index=s)
        >>> obs = gpmsa.ObsData(x=[[0.5]], y=[0.5 * s + 0.3 * s**2])
        >>> fig = gpmsa.plots.data(sim, obs)
        >>> len(fig.axes)     # the runs and experiments, and the colour bar
        2
    """
    if not isinstance(sim, SimData):
        raise GPMSAError(f"sim must be a gpmsa.SimData, got {type(sim).__name__}")
    if obs is not None and not isinstance(obs, ObsData):
        raise GPMSAError(f"obs must be a gpmsa.ObsData or None, got {type(obs).__name__}")
    inputs = [(n, sim.x[:, k], u)
              for k, (n, u) in enumerate(zip(sim.x_names, sim.x_units, strict=True))]  # fmt: skip
    inputs += [(n, sim.t[:, k], u)
               for k, (n, u) in enumerate(zip(sim.t_names, sim.t_units, strict=True))]  # fmt: skip
    names = [n for n, _, _ in inputs]
    if color_by is not None and color_by not in names:  # a scalar output's too, though unused
        raise GPMSAError(f"color_by must be one of the inputs {names}, got {color_by!r}")
    x_obs = None if obs is None else obs.inputs(sim.x_names)
    ys = None if obs is None else obs.outputs(sim.y_names)
    if x_obs is not None and x_obs.shape[1] != sim.p:
        raise GPMSAError(f"obs has {x_obs.shape[1]} known inputs, the runs {sim.p}")
    if sim.l_sim == 1:
        return _scalar(sim, inputs, x_obs, ys)
    if is_map(sim.index, "plots.data"):
        return _maps_of(sim, inputs, obs, ys, color_by)
    return _functional(sim, inputs, obs, ys, color_by)


def _experiment(sim: SimData, obs: ObsData, e: np.ndarray, j: int, grid) -> np.ndarray:
    """Experiment ``j``'s index grid: its own, or the simulation's ``grid``; GPMSAError where it
    has none and its values ``e`` do not match the simulation's."""
    g = obs.output_grids(sim.index_names)[j]
    if g is None and e.size != sim.l_sim:
        raise GPMSAError(
            f"obs experiment {j} has {e.size} values on the simulation grid of {sim.l_sim}: "
            "give its own grid (ObsData(..., index=))"
        )
    return grid if g is None else g


def _y_label(sim: SimData) -> str:
    units = set(sim.y_units)
    unit = units.pop() if len(units) == 1 else ""
    return axis_label("y" if sim.l_sim > 1 else sim.y_names[0], unit)


def _scalar(sim: SimData, inputs, x_obs, ys):
    """One panel per input: the runs' output against it, the experiments on top."""
    fig = figure(2.6 * len(inputs) + 0.4, 2.6)
    axes = fig.subplots(1, len(inputs), squeeze=False)[0]
    observed = None if ys is None else np.array([e[0] for e in ys])
    if ys is not None and any(e.size != 1 for e in ys):
        raise GPMSAError("obs must hold one value per experiment for a scalar output")
    for k, (ax, (name, values, unit)) in enumerate(zip(axes, inputs, strict=True)):
        ax.plot(values, sim.y[:, 0], ".", ms=4, color="C0", label="runs")
        if observed is not None and k < sim.p:
            ax.plot(x_obs[:, k], observed, "o", mfc="none", color=ink(), label="observations")
        elif observed is not None:
            for v in observed:
                ax.axhline(v, color=ink(), lw=0.8)
        ax.set_xlabel(axis_label(name, unit))
    axes[0].set_ylabel(_y_label(sim))
    if observed is not None:
        axes[0].legend(fontsize="x-small")
    return fig


def _functional(sim: SimData, inputs, obs, ys, color_by):
    """The runs over the output grid coloured by ``color_by``, the experiments in black."""
    from matplotlib import cm, colormaps, colors

    names = [n for n, _, _ in inputs]
    color_by = sim.t_names[0] if color_by is None else color_by
    _, values, unit = inputs[names.index(color_by)]
    grid = np.arange(sim.l_sim, dtype=float) if sim.index is None else sim.index
    norm = colors.Normalize(float(np.min(values)), float(np.max(values)))
    cmap = colormaps["viridis"]
    fig = figure(6.4, 3.6)
    ax = fig.subplots()
    for row, v in zip(sim.y, values, strict=True):
        ax.plot(grid, row, color=cmap(norm(v)), lw=0.8, alpha=0.7)
    for j, e in enumerate(ys or ()):
        ax.plot(_experiment(sim, obs, e, j, grid), e, "o-", ms=3, lw=1.2, color=ink(),
                label="observations" if j == 0 else None)  # fmt: skip
    bar = fig.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax)
    bar.set_label(axis_label(color_by, unit))
    ax.set_xlabel(index_labels(sim.index_names, sim.index_units, sim.index)[0])
    ax.set_ylabel(_y_label(sim))
    ax.set_title(f"{sim.m} runs" + ("" if obs is None else f", {obs.n} experiment(s)"),
                 fontsize="small")  # fmt: skip
    if ys:
        ax.legend(fontsize="x-small")
    return fig


def _maps_of(sim: SimData, inputs, obs, ys, color_by):
    """Maps over a two-column index on one colour scale: runs at evenly spaced ranks of
    ``color_by`` (top row), the first experiments at their points (bottom row)."""
    names = [n for n, _, _ in inputs]
    color_by = sim.t_names[0] if color_by is None else color_by
    _, values, unit = inputs[names.index(color_by)]
    ranks = np.unique(np.linspace(0, sim.m - 1, min(MAP_PANELS, sim.m)).round().astype(int))
    runs = np.argsort(values, kind="stable")[ranks]
    grids = [_experiment(sim, obs, e, j, sim.index) for j, e in enumerate(ys or ())]
    shown, grids = list(ys or ())[:MAP_PANELS], grids[:MAP_PANELS]
    norm = _maps.value_norm(sim.y[runs], *shown)
    labels = index_labels(sim.index_names, sim.index_units, sim.index)
    n_cols = max(runs.size, len(shown))
    fig = figure(2.9 * n_cols + 1.0, 2.7 * (1 + bool(shown)) + 0.4)
    panels = fig.add_gridspec(1 + bool(shown), n_cols)
    axes = []
    for c, i in enumerate(runs):
        ax = fig.add_subplot(panels[0, c])
        shade = _maps.surface(ax, sim.index, sim.y[i], norm, _maps.VALUES, labels)
        unit_text = f" {unit}" if unit else ""
        ax.set_title(f"run {i}: {color_by} = {values[i]:.3g}{unit_text}", fontsize="small")
        axes.append(ax)
    for j, (e, g) in enumerate(zip(shown, grids, strict=True)):
        ax = fig.add_subplot(panels[1, j])
        _maps.markers(ax, g, e, norm, _maps.VALUES, background=sim.index, labels=labels)
        ax.set_title(f"experiment {j}", fontsize="small")
        axes.append(ax)
    _maps.colour_bar(fig, shade, axes, _y_label(sim))
    n_obs = "" if obs is None else f", {obs.n} experiment(s) ({len(shown)} shown)"
    fig.suptitle(f"{sim.m} runs ({runs.size} shown, by {color_by}){n_obs}", fontsize="small")
    return fig
