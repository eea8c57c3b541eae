"""full_prediction of a simulation-only fit without posterior=, found by an all-pairs sweep of
the options: a discrepancy= given there was compared with a joint fit's record that does not
exist ("discrepancy='linear' differs from the joint fit's discrepancy (None)"); the refusal
now says what is missing, calibration draws, whatever discrepancy= holds."""

import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError

GRID = np.linspace(0.0, 1.0, 8)


@cache
def _sim_only() -> tuple[gpmsa.Emulator, gpmsa.ObsData]:
    """A simulation-only fit of a functional output (8 values) and two experiments."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(16, 1)), rng.uniform(size=(16, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(2 * (x + t) + GRID), index=GRID)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)  # 20 sweeps: a short chain
        emu = gpmsa.fit(sim, n_iter=20, seed=0, tune=False)
    xo = np.array([[0.3], [0.6]])
    return emu, gpmsa.ObsData(x=xo, y=np.sin(2 * (xo + 0.4) + GRID))


@pytest.mark.parametrize("discrepancy", [None, "constant", "linear", np.ones((8, 1))],
                         ids=["None", "constant", "linear", "array"])  # fmt: skip
def test_a_simulation_only_fit_is_refused_for_its_missing_draws_whatever_the_discrepancy(
    discrepancy,
):
    emu, obs = _sim_only()
    with pytest.raises(GPMSAError, match=r"^full_prediction needs calibration draws: fit "
                                         r"jointly .* or pass posterior="):  # fmt: skip
        gpmsa.full_prediction(emu, obs, [[0.5]], discrepancy=discrepancy)
