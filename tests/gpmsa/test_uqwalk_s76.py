"""Friction found by a user's walkthrough (session 76) on a damped oscillator of their own.

- A two-parameter `Calibrator.update` of one experiment warned that k's posterior "spans 0 node
  spacings" and stored resolution 0.0 for it, while its sd (0.037) matched MCMC's (0.037): the
  marginal's far tail held a bump on one node at 1e-13 of the mass (the oscillator's frequency
  aliasing), and `grid._resolution` read any one-node peak, however light, as unresolved.
- ``pd.DataFrame(y_obs)`` (a frame's default labels 0, 1, ...) was refused by `calibrate` and
  `Calibrator` ("y_obs has the columns ['0', '1', ...]; expected ['y0', ...]"; for 30 of 40
  columns too, naming names, not the count) while ``ObsData(x, pd.DataFrame(y))`` read the same
  frame by position, as docs/calibration.md says.
- ``SimData(x_range=)`` in SEPIA's (2, p) layout (a row of mins, a row of maxs) with p = 2 has
  the shape (p, 2) and was read as one (min, max) per column: "x_range[m] = (0.5, 0.5) must be
  finite numbers with min < max" or "design column m spans [0.51, 2], outside its x_range [0.4,
  0.45]", without the hint the other shapes get (transpose it).
"""

import numpy as np
import pandas as pd
import pytest
from _calib_cases import vector_emulator

import gpmsa
from gpmsa import GPMSAError
from gpmsa.calibration.grid import MODE_MASS, _resolution, resolution


def _peak_with_bump(bump: float) -> tuple[np.ndarray, np.ndarray]:
    """A Gaussian marginal (sd 0.05) on 129 nodes of [0, 1] with a one-node bump of relative
    density ``bump`` at the last node, beyond a gap where the density is below MASS_CUTOFF."""
    axis = np.linspace(0.0, 1.0, 129)
    density = np.exp(-0.5 * ((axis - 0.3) / 0.05) ** 2)
    density[-1] = bump
    return axis, density


def test_negligible_one_node_peak_leaves_the_resolution_alone():
    axis, density = _peak_with_bump(1e-12)
    clean = _resolution(axis, np.where(np.arange(axis.size) == axis.size - 1, 0.0, density))
    assert 6.0 < _resolution(axis, density) == clean  # was 0.0


def test_one_node_peak_with_mass_is_still_unresolved():
    axis, density = _peak_with_bump(10 * MODE_MASS * 0.05 * np.sqrt(2 * np.pi) * 128)
    assert _resolution(axis, density) == 0.0


def test_two_parameter_grid_with_a_negligible_one_node_bump():
    a = np.linspace(0.0, 1.0, 65)
    b = np.linspace(0.0, 1.0, 74)
    logp = -0.5 * ((a[:, None] - 0.5) / 0.06) ** 2 - 0.5 * ((b[None, :] - 0.4) / 0.05) ** 2
    logp[:, -1] = np.log(1e-12) - 0.5 * ((a - 0.5) / 0.06) ** 2
    res = resolution([a, b], logp.ravel())
    assert min(res) > 3.0  # was (3.6, 0.0): "spans 0 node spacings"


def _vector_obs() -> tuple[np.ndarray, np.ndarray]:
    grid = np.linspace(0, 1, 8)
    x = np.array([[0.3], [0.6]])
    return x, 1.5 * np.sin(np.pi * grid[None, :] * (0.5 + x)) + 0.15


def test_default_labelled_y_obs_frame_is_read_by_position_as_obsdata_reads_it():
    emu = vector_emulator()
    x, y = _vector_obs()
    cal = gpmsa.Calibrator(emu)
    ref = cal.log_likelihood_grid(x, y)[1]
    np.testing.assert_array_equal(cal.log_likelihood_grid(x, pd.DataFrame(y))[1], ref)
    via_obs = cal.log_likelihood_grid(gpmsa.ObsData(x, pd.DataFrame(y)))[1]
    np.testing.assert_array_equal(via_obs, ref)
    with pytest.raises(GPMSAError, match=r"y_obs must have shape \(n, 8\), got \(2, 6\)"):
        cal.log_likelihood_grid(x, pd.DataFrame(y[:, :6]))
    with pytest.raises(GPMSAError, match=r"y_obs has the columns \['1', '0'"):  # not default
        cal.log_likelihood_grid(x, pd.DataFrame(y)[[1, 0, 2, 3, 4, 5, 6, 7]])


@pytest.mark.parametrize(
    ("sepia", "why"),
    [([[0.5, 0.5], [2.0, 1.5]], "min < max"), ([[0.4, 0.45], [2.1, 1.6]], "outside its x_range")],
)
def test_square_range_in_sepia_layout_is_named(sepia, why):
    rng = np.random.default_rng(0)
    x = np.column_stack([rng.uniform(0.6, 1.9, 20), rng.uniform(0.55, 1.45, 20)])
    t = rng.uniform(0.0, 1.0, (20, 1))
    y = x[:, :1] + t
    with pytest.raises(GPMSAError, match=rf"{why}.*SEPIA's \(2, 2\) layout.*transpose it"):
        gpmsa.SimData(x=x, t=t, y=y, x_names=["m", "A"], x_range=np.array(sepia))
    assert gpmsa.SimData(x=x, t=t, y=y, x_range=np.array(sepia).T).x_range is not None
    with pytest.raises(
        GPMSAError, match=r"outside its x_range \[0.7, 2\]: the range must hold every run$"
    ):
        gpmsa.SimData(x=x, t=t, y=y, x_names=["m", "A"], x_range=[[0.7, 2.0], [0.5, 1.5]])
