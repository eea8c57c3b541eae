"""A categorical parameter's posterior (`LevelMarginal`) shares no writable array with the
Calibrator, as a `GridMarginal` does not (session 83). Before: its ``nodes`` were the
Calibrator's own level codes, so that recoding the levels in place (``nodes *= 10``) moved every
later posterior of that Calibrator (the mean of the levels 0, 1, 2 read 10x)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import gpmsa
from gpmsa.calibration.posterior import LevelMarginal

sys.path.insert(0, str(Path(__file__).parent))
from _calib_cases import categorical_emulator  # noqa: E402

X_OBS, Y_OBS = [[0.2], [0.7]], [[1.2], [1.7]]  # y = x + 1: level 1


def test_a_level_posterior_shares_no_writable_array_with_the_calibrator():
    cal, twin = gpmsa.Calibrator(categorical_emulator()), gpmsa.Calibrator(categorical_emulator())
    marginal = cal.update(X_OBS, Y_OBS).grids["t0"]
    assert isinstance(marginal, LevelMarginal)
    for name in ("nodes", "density", "weights"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(marginal, name)[:] *= 10.0  # a recoding in place
    later, expected = cal.update(X_OBS, Y_OBS), twin.update(X_OBS, Y_OBS)
    np.testing.assert_array_equal(later.grids["t0"].nodes, [0.0, 1.0, 2.0])
    assert later.mean("t0") == pytest.approx(expected.mean("t0"), rel=1e-12)


def test_from_probabilities_holds_its_own_read_only_arrays():
    levels, p = np.array([0.0, 1.0, 2.0]), np.array([1.0, 2.0, 1.0])
    lm = LevelMarginal.from_probabilities(levels, p)
    assert levels.flags.writeable and p.flags.writeable  # the caller's, as they were
    assert not any(a.flags.writeable for a in (lm.nodes, lm.density, lm.weights))
    levels[:] = 5.0  # the caller's array changes later: the marginal does not
    assert lm.probabilities() == {0.0: 0.25, 1.0: 0.5, 2.0: 0.25}
