"""calibrate_study warns, naming the model, where a model's observations lie outside what its
emulator has seen (a units error), as gpmsa.calibrate does; it was silent before session 62."""

from __future__ import annotations

import warnings

import pytest

import gpmsa
from gpmsa.errors import OutsideEmulatorWarning
from tests.gpmsa import _study_cases as sc

INSIDE = float(sc.simulator(0.5, 0.4))


def _study(y_b, **kw):
    emu = sc.emulator()
    return gpmsa.calibrate_study(
        [emu, emu], [[[0.5]], [[0.5]]], [[INSIDE], [y_b]], labels=["a", "b"], shared=["t"],
        n_samples=60, n_burn=10, tune=False, seed=1, **kw,
    )  # fmt: skip


def test_a_models_observation_outside_its_emulator_is_named():
    far = 1e3 * INSIDE
    with pytest.warns(OutsideEmulatorWarning, match=r"model 'b': y_obs lies .* predictive sds"):
        _study(far)
    with pytest.warns(OutsideEmulatorWarning, match=r"model 'b': .*The discrepancy term"):
        _study(far, discrepancy=[None, "constant"])
    with warnings.catch_warnings():
        warnings.simplefilter("error", OutsideEmulatorWarning)
        _study(INSIDE)  # inside: no warning
