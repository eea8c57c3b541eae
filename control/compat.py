"""Checks that an emulator suits the loop it is asked to serve (vehicle, noise, feature, domain).

The training script records in ``emulator.metadata``: ``vehicle`` (``model.describe()``),
``noise_std`` (m/s^2), ``feature`` (``{"name": ..., "window_samples": ..., "rate_hz": ...}``, see
`control.feature`) and ``road`` (the campaign's road settings).
"""

from __future__ import annotations

import json
import warnings

import numpy as np

from control.bcr import BCRSettings
from control.errors import ControlWarning, EmulatorMismatchError


def _canon(obj) -> str:
    return json.dumps(obj, sort_keys=True, default=str)


def check_emulator(
    emulator,
    *,
    model=None,
    noise_std: float | None = None,
    bcr: BCRSettings | None = None,
    track=None,
) -> None:
    """Raise `EmulatorMismatchError` or warn (`ControlWarning`) where the emulator does not fit.

    Errors: another vehicle model; another feature (name, window length, rate); a track whose
    prescribed GD lies outside the emulator's GD domain. Warnings: a different noise level (the
    paper's Test Cases pair the noise-free emulator with noise-free data and the noisy one with
    noisy data; a mismatch biases GD, but a robustness study may want it); metadata missing.
    """
    meta = dict(getattr(emulator, "metadata", None) or {})
    if model is not None:
        if "vehicle" not in meta:
            warnings.warn(
                "emulator metadata has no 'vehicle'; cannot check it was made for "
                f"{model.describe().get('model', type(model).__name__)}",
                ControlWarning,
                stacklevel=3,
            )
        elif _canon(meta["vehicle"]) != _canon(model.describe()):
            raise EmulatorMismatchError(
                f"emulator was made for vehicle {_canon(meta['vehicle'])}, "
                f"not for model {_canon(model.describe())}"
            )
    if noise_std is not None:
        if "noise_std" not in meta:
            warnings.warn("emulator metadata has no 'noise_std'", ControlWarning, stacklevel=3)
        elif not np.isclose(float(meta["noise_std"]), float(noise_std)):
            warnings.warn(
                f"noise_std = {noise_std:g} m/s^2 in the data but the emulator was trained with "
                f"noise_std = {float(meta['noise_std']):g}: the GD estimates will be biased",
                ControlWarning,
                stacklevel=3,
            )
    if bcr is not None and "feature" in meta:
        feat = meta["feature"]
        expected = {  # emulator metadata key: (BCR setting, its value)
            "window_samples": ("buffer", bcr.buffer),
            "rate_hz": ("rate_hz", bcr.rate_hz),
            "name": ("feature", bcr.feature),
        }
        for key, (setting, value) in expected.items():
            if key not in feat or feat[key] == value:
                continue
            if not isinstance(value, str) and np.isclose(float(feat[key]), float(value)):
                continue
            raise EmulatorMismatchError(
                f"BCR {setting} = {value!r} but the emulator's feature has {key} = {feat[key]!r}"
            )
    if track is not None:
        lo, hi = emulator.domain[emulator.t_names[0]]
        gds = [gd for _, gd in track.segments]
        outside = [gd for gd in gds if not lo <= gd <= hi]
        if outside:
            raise EmulatorMismatchError(
                f"track GD {outside} outside the emulator's GD domain [{lo:g}, {hi:g}]"
            )


def bcr_settings_for(emulator, **overrides) -> BCRSettings:
    """BCR settings matching the emulator's recorded feature (name, window, rate)."""
    feat = dict((getattr(emulator, "metadata", None) or {}).get("feature", {}))
    kwargs = {}
    if "window_samples" in feat:
        kwargs["buffer"] = int(feat["window_samples"])
    if "rate_hz" in feat:
        kwargs["rate_hz"] = float(feat["rate_hz"])
    if "name" in feat:
        kwargs["feature"] = str(feat["name"])
    kwargs.update(overrides)
    return BCRSettings(**kwargs)
