"""A lamOs prior with an upper bound (a known observation precision): the MCMC's start of lamOs
and the grid posterior's lamOs draws stay inside the prior's support."""

import warnings
from dataclasses import replace

import numpy as np
import pytest
from _calib_cases import road_emulator

import gpmsa
from gpmsa import Calibrator
from gpmsa.calibration.model import LamOsPrior
from gpmsa.calibration.observations import Fit, lamos_start
from tests.gpmsa._emulator_edit import replaced

LAM0 = 400.0


def known_precision_emulator(lower: float, upper: float):
    """The road emulator with its lamOs prior cut to (lower, upper)."""
    emu = road_emulator()
    return replaced(
        emu, priors=replace(emu.priors, lamOs=replace(emu.priors.lamOs, lower=lower, upper=upper))
    )


def window():
    rng = np.random.default_rng(5)
    v = np.linspace(0.6, 1.9, 10)[:, None]
    return v, 0.02 * 450 * v**1.6 * (1 + 0.003 * rng.standard_normal(v.shape))


@pytest.mark.parametrize(
    "lower, upper", [(0.0, 5.0), (0.0, 500.0), (LAM0 * 0.999, LAM0 * 1.001), (100.0, 100.5)]
)
def test_the_lamos_start_lies_inside_the_prior(lower, upper):
    """The start was max(20, a/b) (1000 for the default prior) whatever the upper bound."""
    prior = LamOsPrior(1.0, 1e-3, lower, upper)
    start = lamos_start(Fit(0.0, 0.0), prior)
    assert lower < start < upper


def test_unbounded_lamos_starts_are_unchanged():
    prior = LamOsPrior(1.0, 1e-3)
    assert lamos_start(Fit(0.0, 0.0), prior) == 1000.0
    assert lamos_start(Fit(0.0, 0.0), LamOsPrior(1.0, 1e-3, 5.0)) == 1000.0
    assert lamos_start(Fit(0.0, 0.01), prior) == pytest.approx(100.0)


def test_calibrate_runs_with_a_known_observation_precision_and_matches_the_grid():
    """calibrate raised 'the posterior has no mass where the sampler looked': its lamOs chain
    started at 1000, above the prior's upper bound 400.4."""
    emu = known_precision_emulator(LAM0 * 0.999, LAM0 * 1.001)
    x, y = window()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        mcmc = gpmsa.calibrate(emu, x, y, n_samples=6000, n_burn=1000, seed=2)
    grid = Calibrator(emu, seed=1).update(x, y)
    lam = mcmc.samples["lamOs"]
    assert np.all((lam > LAM0 * 0.999) & (lam < LAM0 * 1.001))
    assert abs(np.mean(mcmc.samples["GD"]) - grid.mean("GD")) < 0.2 * grid.sd("GD")


def test_grid_lamos_draws_stay_inside_a_truncated_prior():
    """The draws' jitter of half a log-lamOs step reached past the end nodes, which lie on the
    bounds: 51 % of the draws lay outside (399.6, 400.4)."""
    emu = known_precision_emulator(LAM0 * 0.999, LAM0 * 1.001)
    lam = Calibrator(emu, seed=1).update(*window()).samples["lamOs"]
    assert np.all((lam > LAM0 * 0.999) & (lam < LAM0 * 1.001))
    assert lam.std() > 0.1  # spread over the window, not piled on one value
