"""Bars of Sobol main and total effects (and, for a functional output, along its grid)."""

from __future__ import annotations

import warnings

import numpy as np

from gpmsa.errors import GPMSAError
from gpmsa.model.data import check_level
from gpmsa.plots._figure import figure
from gpmsa.predictive.sobol import Sensitivity


def sensitivity_bars(sens: Sensitivity, *, level: float = 0.9):
    """Main- and total-effect indices per input with their spread over posterior draws.

    Left: bars of the aggregated indices (mean over draws) with the central interval of
    probability ``level`` over draws as error bars (the interval itself: a skewed spread over
    draws can leave the mean outside it). Right (a functional output): main (solid)
    and total (dashed) effect of each input along the output grid, with their bands.

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
    functional = sens.grid.size > 1
    fig = figure(11.0 if functional else 5.5, 4.0)
    axes = fig.subplots(1, 2 if functional else 1, squeeze=False)[0]
    d = len(sens.names)
    pos = np.arange(d)
    for off, kind, arr, color in ((-0.2, "main", sens.main_aggregated, "C0"),
                                  (0.2, "total", sens.total_aggregated, "C1")):  # fmt: skip
        lo, hi = np.quantile(arr, q, axis=0)
        axes[0].bar(pos + off, arr.mean(axis=0), width=0.4, color=color, label=f"{kind} effect")
        # the interval [lo, hi] itself: a skewed spread can leave the mean outside it
        axes[0].errorbar(pos + off, (lo + hi) / 2, yerr=(hi - lo) / 2, fmt="none", ecolor="k",
                         capsize=3)  # fmt: skip
    axes[0].set_xticks(pos, sens.names)
    axes[0].set_ylim(0.0, 1.05)
    axes[0].set_ylabel("Sobol index")
    title = "aggregated over the output grid" if functional else "Sobol indices"
    spread = (" (the point estimate)" if list(np.ravel(sens.draw_index)) == [-1]
              else f"; bars: {100 * level:.0f} % over {sens.main.shape[0]} draws")  # fmt: skip
    axes[0].set_title(title + spread, fontsize="small")
    axes[0].legend(fontsize="small")
    if functional:
        ax = axes[1]
        with warnings.catch_warnings():  # all-NaN grid points (zero output variance)
            warnings.simplefilter("ignore", RuntimeWarning)
            for k, name in enumerate(sens.names):
                for arr, style in ((sens.main, "-"), (sens.total, "--")):
                    col = arr[:, :, k]
                    ax.plot(sens.grid, np.nanmean(col, axis=0), style, color=f"C{k}",
                            label=name if style == "-" else None)  # fmt: skip
                    if col.shape[0] > 1:
                        lo, hi = np.nanquantile(col, q, axis=0)
                        ax.fill_between(sens.grid, lo, hi, color=f"C{k}", alpha=0.15)
        ax.set_ylim(0.0, 1.05)
        ax.set_xlabel("output index")
        ax.set_ylabel("index (solid: main, dashed: total)")
        ax.legend(fontsize="small")
    return fig
