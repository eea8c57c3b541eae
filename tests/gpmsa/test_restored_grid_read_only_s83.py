"""A Calibrator's ``theta_grid`` stays read-only through pickle and ``copy.deepcopy`` (session
83). Before: numpy restores an array writable, so that a restored Calibrator (a saved window
BCR's model) took a write into its grid, which its ``log_likelihood_grid`` then handed to every
later update (a BCR's GD tracker reads its likelihood on that grid)."""

import copy
import pickle

import pytest
from _calib_cases import road_emulator, road_obs

import gpmsa


@pytest.mark.parametrize("restore", [lambda c: pickle.loads(pickle.dumps(c)), copy.deepcopy],
                         ids=["pickle", "deepcopy"])  # fmt: skip
def test_a_restored_calibrators_grid_is_read_only(restore):
    cal = gpmsa.Calibrator(road_emulator())
    twin = restore(cal)
    with pytest.raises(ValueError, match="read-only"):
        twin.theta_grid *= 1e-6  # a unit conversion in place
    grid, _ = twin.log_likelihood_grid(*road_obs())
    assert grid[-1] == cal.theta_grid[-1]
