"""Prediction, sensitivity and cross-validation with a fitted (and calibrated) emulator.

- ``calibrated_predict``: the output's predictive at new x averaged over a calibration posterior.
- ``emulator_prediction``: draws of the simulator output at new (x, t), per posterior draw
  (SEPIA's emulator prediction).
- ``full_prediction``: the calibrated prediction at new x, split into the simulator eta, the
  discrepancy delta and a new observation y (SEPIA's full prediction).
- ``calibration_posterior``: a joint fit's calibration draws as a ``Posterior``.
- ``sensitivity``: Sobol main and total effects of the emulator (GPM/SA's gSens).
- ``cross_validate``: leave-one-out and k-fold predictions over the posterior draws.
"""

from gpmsa.predictive.calibrated import CalibratedPrediction, calibrated_predict
from gpmsa.predictive.crossval import CrossValidation, cross_validate
from gpmsa.predictive.emulator_draws import EmulatorPrediction, emulator_prediction
from gpmsa.predictive.full import FullPrediction, full_prediction
from gpmsa.predictive.joint import calibration_posterior
from gpmsa.predictive.sobol import Sensitivity, sensitivity

__all__ = [
    "CalibratedPrediction",
    "CrossValidation",
    "EmulatorPrediction",
    "FullPrediction",
    "Sensitivity",
    "calibrated_predict",
    "calibration_posterior",
    "cross_validate",
    "emulator_prediction",
    "full_prediction",
    "sensitivity",
]
