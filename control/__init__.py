"""Bayesian Calibration Routine (BCR), Simplex speed controller and the closed loop.

Note: the import name ``control`` is also python-control's; do not install both in one environment.
"""
