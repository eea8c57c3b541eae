"""Bayesian Calibration Routine (BCR), Simplex speed controller and the closed loop.

>>> import control
>>> emu = control.shipped_emulator("A")                     # doctest: +SKIP
>>> track = roadgen.track([(50, 300), (50, 500), (50, 300)], seed=1)   # doctest: +SKIP
>>> result = control.run_closed_loop(track, emu, seed=1)    # doctest: +SKIP
>>> result.metrics.rmse(300), result.metrics.rmse(500)      # doctest: +SKIP

Note: the import name ``control`` is also python-control's; do not install both in one environment.
"""

from control.bcr import BCR, BCRSettings
from control.closed_loop import ClosedLoopResult, LoopMetrics, SensorFault, run_closed_loop
from control.compat import bcr_settings_for, check_emulator
from control.errors import ControlError, ControlWarning, EmulatorMismatchError
from control.estimate import STATUSES, Estimate
from control.feature import window_feature
from control.metrics import GDError, detection_delays, fast_on_rough_m, gd_errors, pooled_rmse
from control.shipped import shipped_emulator, shipped_emulator_path
from control.simplex import Command, Simplex
from control.tracker import GDTracker, TrackerSettings

__all__ = [
    "BCR",
    "BCRSettings",
    "STATUSES",
    "ClosedLoopResult",
    "Command",
    "ControlError",
    "ControlWarning",
    "EmulatorMismatchError",
    "Estimate",
    "GDError",
    "GDTracker",
    "LoopMetrics",
    "SensorFault",
    "Simplex",
    "TrackerSettings",
    "bcr_settings_for",
    "check_emulator",
    "detection_delays",
    "fast_on_rough_m",
    "gd_errors",
    "pooled_rmse",
    "run_closed_loop",
    "shipped_emulator",
    "shipped_emulator_path",
    "window_feature",
]
