"""Review of the day's changes (s57): an object with the attributes calibration checks for
(``check_emulator``) but no ``model_sha256`` — not a gpmsa.Emulator — was calibrated as before
the posterior recorded its emulator; since, ``Calibrator.update`` and ``gpmsa.calibrate``
(after all its sampling) raised a bare AttributeError, and ``calibrated_predict`` with a
posterior that recorded its emulator did too."""

from __future__ import annotations

import sys
import types
from pathlib import Path

import numpy as np
import pytest

import gpmsa
from gpmsa.predictive import calibrated_predict

sys.path.insert(0, str(Path(__file__).parent))
from _study_cases import emulator, observations  # noqa: E402


def stand_in(emu: gpmsa.Emulator) -> types.SimpleNamespace:
    """A stand-in with the emulator's attributes (and properties), not its model_sha256."""
    out = types.SimpleNamespace(**{k: v for k, v in vars(emu).items() if k != "model_sha256"})
    for name in ("p", "q", "p_u", "zt", "categorical", "categorical_mask", "domain", "units"):
        if hasattr(emu, name):
            setattr(out, name, getattr(emu, name))
    return out


def test_a_stand_in_is_calibrated_without_a_record():
    emu = emulator()
    duck = stand_in(emu)
    x, y = observations(0.6, 6, 0.02, np.random.default_rng(0))
    grid = gpmsa.Calibrator(duck).update(x, y)
    mcmc = gpmsa.calibrate(duck, x, y, n_samples=60, n_burn=10, tune=False, seed=0)
    for post in (grid, mcmc):
        assert "emulator_sha256" not in post.info  # nothing to record
        calibrated_predict(emu, post, [[0.5]])  # and so nothing to refuse
    assert grid.mean("t") == gpmsa.Calibrator(emu).update(x, y).mean("t")


def test_a_stand_in_with_a_recorded_posterior_is_a_clear_error():
    emu = emulator()
    x, y = observations(0.6, 6, 0.02, np.random.default_rng(0))
    post = gpmsa.Calibrator(emu).update(x, y)
    with pytest.raises(gpmsa.GPMSAError, match=r"posterior= records the gpmsa\.Emulator .*"
                       r"SimpleNamespace"):  # fmt: skip
        calibrated_predict(stand_in(emu), post, [[0.5]])
