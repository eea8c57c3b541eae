"""The observation y the BCR gives the calibrator, computed from one window of accelerations.

Features (the emulator records which one it was trained on; training and BCR agree through it):

- ``"var"``: f = var(a) normalised by T (the paper's eq. 5);
- ``"log_var"``: log f (default). The window-to-window scatter of f across road realisations is
  multiplicative (a CV of ~15-25%), so log f has a near-constant spread that the GP nugget can
  describe, and the likelihood of GD is closer to Gaussian.
"""

from __future__ import annotations

import numpy as np

from control.errors import ControlError

FEATURES = ("var", "log_var")


def window_feature(accel: np.ndarray, feature: str = "log_var") -> float:
    """The observation y of one window.

    Args:
        accel: (T,) vertical front-axle accelerations, m/s^2.
        feature: "var" or "log_var" (see the module docstring).

    Returns:
        y; NaN for "log_var" of a window with zero variance.
    """
    if feature not in FEATURES:
        raise ControlError(f"feature must be one of {FEATURES}, got {feature!r}")
    accel = np.asarray(accel, dtype=float)
    if accel.ndim != 1 or accel.size < 2:
        raise ControlError(f"accel must be 1-D with >= 2 samples, got shape {accel.shape}")
    f = float(np.var(accel))  # normalised by T, as the paper's eq. 5
    if feature == "log_var":
        return float(np.log(f)) if f > 0 else np.nan
    return f
