"""Calibration with the emulator fixed: the calibration-only model, the observations, the fast
sampler, ``calibrate`` (MCMC), the streaming ``Calibrator`` and the ``Posterior`` they return.
"""
