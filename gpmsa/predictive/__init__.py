"""Prediction with a calibrated emulator (``gpmsa.predictive.calibrated_predict``)."""

from gpmsa.predictive.calibrated import CalibratedPrediction, calibrated_predict

__all__ = ["CalibratedPrediction", "calibrated_predict"]
