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
    accel = np.asarray(accel, dtype=float)
    if accel.ndim != 1 or accel.size < 2:
        raise ControlError(f"accel must be 1-D with >= 2 samples, got shape {accel.shape}")
    return float(feature_of_variance(np.var(accel), feature))  # var: normalised by T (eq. 5)


def feature_of_variance(f: np.ndarray | float, feature: str = "log_var") -> np.ndarray | float:
    """The observation y of windows whose variance (normalised by T) is ``f``, (m/s^2)^2.

    The one map from f to y, shared by the BCR (``window_feature``) and emulator training, so
    that both see the same quantity. "log_var" of f <= 0 is NaN.
    """
    if feature not in FEATURES:
        raise ControlError(f"feature must be one of {FEATURES}, got {feature!r}")
    f = np.asarray(f, dtype=float)
    if feature == "var":
        return f[()]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(f > 0, np.log(np.where(f > 0, f, 1.0)), np.nan)[()]
