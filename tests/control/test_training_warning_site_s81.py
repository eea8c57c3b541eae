"""Warnings of the fit under `control.training.fit_band_emulator` / `fit_window_emulator` (a
ConvergenceWarning of a short fit, say) pointed at a line of control/training.py, where
gpmsa's own frames end, not at the user's call that made the fit."""

import warnings

import numpy as np
import pytest

import gpmsa
from control.training import fit_band_emulator, fit_window_emulator

SPEEDS = np.repeat([0.6, 0.9, 1.2, 1.5, 1.8], 3)
GDS = np.tile([200.0, 400.0, 600.0], 5)


def drives(seed: int = 0) -> np.ndarray:
    """(15, 2000) accelerations whose level grows with GD and speed, plus white noise."""
    rng = np.random.default_rng(seed)
    level = np.sqrt(GDS * SPEEDS)[:, None] / 5.0
    shape = (SPEEDS.size, 2000)
    return level * rng.standard_normal(shape) + 0.3 * rng.standard_normal(shape)


@pytest.mark.parametrize(
    ("fit", "options"),
    [(fit_band_emulator, {"n_pc": 2}), (fit_window_emulator, {})],
)
def test_a_fits_warning_points_at_the_users_call(fit, options):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fit(SPEEDS, GDS, drives(), noise_std=0.3, n_iter=30, seed=0, **options)
    converge = [w for w in caught if issubclass(w.category, gpmsa.ConvergenceWarning)]
    assert converge, [str(w.message) for w in caught]  # 30 sweeps: too short to judge
    assert {w.filename for w in caught} == {__file__}, [(w.filename, w.lineno) for w in caught]


def test_the_callers_filters_still_apply():
    """An "error" filter still turns the fit's warning into an exception at the caller."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", gpmsa.ConvergenceWarning)
        with pytest.raises(gpmsa.ConvergenceWarning):
            fit_window_emulator(SPEEDS, GDS, drives(), noise_std=0.3, n_iter=30, seed=0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        fit_window_emulator(SPEEDS, GDS, drives(), noise_std=0.3, n_iter=30, seed=0)
    assert not [w for w in caught if issubclass(w.category, gpmsa.ConvergenceWarning)]
