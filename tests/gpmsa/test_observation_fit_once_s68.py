"""The observation's fit over the theta probe (its outside check and lamOs start) is computed once
per model: ``calibrate(fast=False)`` and ``calibrate_study`` computed it a second time inside
``calibration_problem`` (~80 ms a model on 200 runs and two parameters; session 68)."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.calibration import calibrate as calibrate_mod
from gpmsa.errors import GPMSAError


@pytest.fixture(scope="module")
def emulator():
    rng = np.random.default_rng(0)
    x, t = rng.random((30, 1)), rng.random((30, 1))
    sim = gpmsa.SimData(x, t, (x[:, 0] + t[:, 0])[:, None])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(sim, n_iter=60, seed=1)


@pytest.fixture
def calls(monkeypatch):
    seen = []
    fit = calibrate_mod.observation_fit

    def counted(*args):
        seen.append(1)
        return fit(*args)

    monkeypatch.setattr(calibrate_mod, "observation_fit", counted)
    return seen


X_OBS = np.array([[0.2], [0.5], [0.8]])


def test_generic_calibration_fits_the_observation_once(emulator, calls):
    gpmsa.calibrate(emulator, X_OBS, X_OBS[:, 0] + 0.4, n_samples=20, n_burn=5, seed=0,
                    fast=False)  # fmt: skip
    assert len(calls) == 1  # 2 before


def test_a_calibration_study_fits_each_observation_once(emulator, calls, monkeypatch):
    from gpmsa.studies import run

    monkeypatch.setattr(run, "observation_fit", calibrate_mod.observation_fit)
    gpmsa.calibrate_study([emulator, emulator], [X_OBS, X_OBS], [X_OBS[:, 0] + 0.4] * 2,
                          labels=["a", "b"], shared=[emulator.t_names[0]], n_samples=20,
                          n_burn=5, seed=0)  # fmt: skip
    assert len(calls) == 2  # 4 before


def test_a_fit_without_its_reduction_is_refused(emulator):
    with pytest.raises(GPMSAError, match="fit= is the fit of reduced="):
        calibrate_mod.calibration_problem(emulator, X_OBS, X_OBS[:, 0], fit=object())
