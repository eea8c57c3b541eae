"""Exact checks of ``calibrated_predict`` from session 92's mutation testing of the odd half of
gpmsa/predictive/calibrated.py's sites: its flags are checked by name before use, and a grid
posterior's weights sum to 1 after the nodes below 1e-12 of the largest mass are cut."""

import numpy as np
import pytest
from _predict_cases import four_run_emulator

import gpmsa
from gpmsa import GPMSAError
from gpmsa.calibration.posterior import GridMarginal

X2 = [[0.2], [0.8]]


@pytest.mark.parametrize(
    ("option", "value", "x_new"),
    [("noise", "yes", X2), ("resid", 2, X2), ("extrapolate", "no", [[2.0]])],
)
def test_flags_are_refused_by_name_unless_true_or_false(option, value, x_new):
    """A string or an int is not read as a flag (not even a truthy one, which would add noise,
    or let x_new = 2 lie 100 % beyond the x range)."""
    post = gpmsa.Posterior({"t": np.array([0.2, 0.4]), "lamOs": np.array([1.0, 2.0])})
    with pytest.raises(GPMSAError, match=f"{option} must be True or False"):
        gpmsa.calibrated_predict(four_run_emulator(), post, x_new, **{option: value})


def test_grid_weights_sum_to_one_after_the_cut():
    """2001 nodes, one of density 1 and 2000 of 5e-13 (mass 5e-13 of the largest: cut): the cut
    mass is ~1e-9 of the total, so the one live node's weight is exactly 1 only if the kept
    masses are renormalised (multiplying by their sum instead gives 1 - 2e-9)."""
    emu = four_run_emulator()
    nodes = np.linspace(0.0, 1.0, 2001)
    log_f = np.full(2001, np.log(5e-13))
    log_f[1000] = 0.0
    g = GridMarginal.from_log_density(nodes, log_f)
    post = gpmsa.Posterior({"t": np.array([0.5])}, grids={"t": g})
    p = gpmsa.calibrated_predict(emu, post, X2)
    assert p.weights.tolist() == [1.0]
    mean, var = emu.predict(X2, np.full((2, 1), 0.5))
    np.testing.assert_allclose(p.mean, mean, rtol=1e-14)
    np.testing.assert_allclose(p.var, var, rtol=1e-14)
