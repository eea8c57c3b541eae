"""Figures users look at: the data before fitting, MCMC traces and autocorrelations, theta
pairs, the PC basis and the observations' projection onto it (per component and in pairs), rho
box plots, emulator fit, prediction bands, sensitivity bars and main-effect curves. The figures
that draw along the output index draw maps over an index of two columns (SEPIA's (time, angle)
y_ind; ``gpmsa.plots._maps``).

Each function returns a ``matplotlib.figure.Figure`` (matplotlib is imported only when one runs;
nothing is shown): ``fig.savefig("trace.png")`` in a script, or display it in a notebook.
"""

from gpmsa.plots.data import data
from gpmsa.plots.emulator import emulator_fit, pc_basis
from gpmsa.plots.mcmc import autocorrelation, theta_pairs, traces
from gpmsa.plots.observations import obs_projection, weight_pairs
from gpmsa.plots.prediction import prediction_bands
from gpmsa.plots.rho import rho_boxplots
from gpmsa.plots.sensitivity import main_effect_curves, sensitivity_bars

__all__ = [
    "autocorrelation",
    "data",
    "emulator_fit",
    "main_effect_curves",
    "obs_projection",
    "pc_basis",
    "prediction_bands",
    "rho_boxplots",
    "sensitivity_bars",
    "theta_pairs",
    "traces",
    "weight_pairs",
]
