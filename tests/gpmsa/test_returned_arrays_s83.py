"""Arrays a Calibrator hands out do not alias its state. Before: ``log_likelihood_grid`` returned
the Calibrator's own ``theta_grid``, and a grid posterior's ``nodes`` and ``weights`` were the
Calibrator's (or a control filter's) grid and trapezoid weights, so that writing into a returned
array (a unit conversion in place) changed every later posterior of that Calibrator."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import gpmsa
from gpmsa.calibration.posterior import GridMarginal

sys.path.insert(0, str(Path(__file__).parent))
from _calib_cases import road_emulator, road_obs  # noqa: E402


@pytest.fixture(scope="module")
def calibrators() -> tuple[gpmsa.Calibrator, gpmsa.Calibrator]:
    emu = road_emulator()
    return gpmsa.Calibrator(emu), gpmsa.Calibrator(emu)


def test_log_likelihood_grid_returns_a_grid_the_caller_cannot_write(calibrators):
    cal, twin = calibrators
    x, y = road_obs()
    grid, loglik = cal.log_likelihood_grid(x, y)
    with pytest.raises(ValueError, match="read-only"):
        grid *= 1e-6  # a unit conversion in place
    loglik[:] = 0.0  # a new array each call: the caller's to change
    again, twin_grid = cal.log_likelihood_grid(x, y)[0], twin.log_likelihood_grid(x, y)[0]
    np.testing.assert_array_equal(again, twin_grid)


def test_a_grid_posterior_shares_no_writable_array_with_the_calibrator(calibrators):
    cal, twin = calibrators
    x, y = road_obs()
    marginal = cal.update(x, y).grids["GD"]
    for name in ("nodes", "density", "weights"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(marginal, name)[:3] = 1.0
    later, expected = cal.update(x, y), twin.update(x, y)
    assert later.mean("GD") == pytest.approx(expected.mean("GD"), rel=1e-12)
    assert later.sd("GD") == pytest.approx(expected.sd("GD"), rel=1e-12)


def test_from_log_density_holds_its_own_read_only_arrays():
    nodes, weights = np.linspace(1.0, 2.0, 5), np.full(5, 0.25)
    gm = GridMarginal.from_log_density(nodes, np.zeros(5), weights)
    assert nodes.flags.writeable and weights.flags.writeable  # the caller's, as they were
    assert not (gm.nodes.flags.writeable or gm.weights.flags.writeable)
    nodes[:], weights[:] = 0.0, 1.0  # the caller's arrays change later: the marginal does not
    assert gm.nodes[0] == 1.0 and gm.weights[0] == 0.25 and gm.mean() == pytest.approx(1.5)
