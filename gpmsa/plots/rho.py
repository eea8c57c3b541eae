"""Box plots of the emulator's correlation parameters on the rho scale (SEPIA's
``SepiaPlot.rho_box_plots``, GPM/SA's rho boxplots)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from gpmsa._fp_state import underflow_as_zero
from gpmsa.errors import GPMSAError
from gpmsa.fitting.emulator import Emulator
from gpmsa.model.correlation import beta_to_rho
from gpmsa.model.data import check_count
from gpmsa.plots._figure import figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def _rho_panels(emulator: Emulator, max_pc: int) -> np.ndarray:
    """rho = exp(-betaU/4) of the retained draws, one panel per component (at most ``max_pc``):
    (n_panels, n_draws, p + q); GPMSAError for an emulator without draws of betaU."""
    if not isinstance(emulator, Emulator):
        raise GPMSAError(f"emulator must be a gpmsa.Emulator, got {type(emulator).__name__}")
    max_pc = check_count(max_pc, "max_pc")
    beta = emulator.draws.get("betaU")
    if emulator.n_draws == 0 or beta is None:
        raise GPMSAError(
            "this emulator kept no posterior draws of betaU to plot (an Emulator.from_params "
            "has none; fit one with gpmsa.fit)"
        )
    beta = np.asarray(beta, dtype=float)[:, :, : min(emulator.p_u, max_pc)]
    return np.moveaxis(beta_to_rho(beta), 2, 0)


@underflow_as_zero  # rho of a rough input's large beta underflows to 0
def rho_boxplots(emulator: Emulator, *, max_pc: int = 6) -> Figure:
    """Posterior box plots of rho = exp(-betaU/4) per input, one panel per basis component (at
    most ``max_pc``): a Figure.

    rho is the correlation of the component's weights between two runs half the unit-scaled
    range of that input apart (all else equal): near 1, the input hardly matters for that
    component; smaller, it matters more. A categorical input (labelled "NAME (cat.)") has rho
    = the correlation between two different levels (gpmsa.model.correlation). The boxes are
    the known inputs x, then the calibration inputs t, from the emulator's retained draws.

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1))
        >>> data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t, x_names=["x"], t_names=["t"])
        >>> emu = gpmsa.fit(data, n_iter=50, tune=False, seed=0)
        >>> fig = gpmsa.plots.rho_boxplots(emu)
        >>> [lab.get_text() for lab in fig.axes[0].get_xticklabels()]
        ['x', 't']
    """
    panels = _rho_panels(emulator, max_pc)
    cat = emulator.categorical
    labels = [f"{n} (cat.)" if n in cat else n for n in emulator.x_names + emulator.t_names]
    fig = figure(max(4.0, 0.6 * len(labels) + 1.5), 2.2 * len(panels) + 0.4)
    axes = fig.subplots(len(panels), 1, squeeze=False)[:, 0]
    for j, (ax, rho) in enumerate(zip(axes, panels, strict=True)):
        ax.boxplot(rho, flierprops={"markersize": 2})
        ax.set_xticks(np.arange(1, len(labels) + 1), labels)
        ax.set_ylim(-0.02, 1.02)  # [0, 1], boxes at the edges visible
        ax.set_ylabel("rho")
        ax.set_title(f"PC {j + 1}", fontsize="small")
    return fig
