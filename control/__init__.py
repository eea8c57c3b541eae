"""Bayesian Calibration Routine (BCR), Simplex speed controller and the closed loop.

>>> import control, roadgen
>>> emu = control.shipped_emulator("A")                     # doctest: +SKIP
>>> track = roadgen.track([(50, 300), (50, 500), (50, 300)], seed=1)   # doctest: +SKIP
>>> result = control.run_closed_loop(track, emu, seed=1)    # doctest: +SKIP
>>> result.metrics.rmse(300), result.metrics.rmse(500)      # doctest: +SKIP

Note: the import name ``control`` is also python-control's; do not install both in one environment.
"""

from control.bcr import BCR, INTERVAL_KINDS, METHODS, PAPER_WINDOW, BCRSettings
from control.changepoint import ChangePointFilter, ChangePointSettings
from control.closed_loop import ClosedLoopResult, LoopMetrics, run_closed_loop
from control.compat import (
    bcr_settings_for,
    check_emulator,
    check_likelihood,
    emulator_feature,
    emulator_noise_std,
    emulator_vehicle,
)
from control.errors import (
    BagError,
    ControlError,
    ControlWarning,
    EmulatorMismatchError,
    MissingExtraError,
)
from control.estimate import DOMAIN_EDGES, FAULT_STATUSES, STATUSES, Estimate, edge_counts
from control.faults import FAULT_KINDS, FaultInjector, SensorFault
from control.feature import FeatureSpec, block_features, window_feature
from control.metrics import (
    GDError,
    clustered_mean,
    detection_delays,
    fast_on_rough_m,
    gd_errors,
    interval_coverage,
    pooled_rmse,
)
from control.observation_model import BlockScatter, ObservationModel
from control.robot import ReplayResult, ReplaySettings, record_run, replay_bag
from control.sensor_checks import SensorLimits
from control.shipped import shipped_emulator, shipped_emulator_path
from control.simplex import Command, Simplex, SimplexRun
from control.tracker import GDTracker, TrackerSettings

__gpmsa_wrapper__ = True
"""gpmsa's warnings under control's calls (a BCR's calibration) point at the user's line that
made the call, not at a line of control (``gpmsa.errors.WRAPPER_MARK``)."""
__vehicle_wrapper__ = True
"""vehicle's warnings under control's calls (a `vehicle.SolverStepWarning` of the closed loop's
simulation) point at the user's line (``vehicle.errors.WRAPPER_MARK``)."""

__all__ = [
    "BCR",
    "BCRSettings",
    "BagError",
    "DOMAIN_EDGES",
    "FAULT_KINDS",
    "FAULT_STATUSES",
    "INTERVAL_KINDS",
    "METHODS",
    "PAPER_WINDOW",
    "STATUSES",
    "BlockScatter",
    "ChangePointFilter",
    "ChangePointSettings",
    "ClosedLoopResult",
    "Command",
    "ControlError",
    "ControlWarning",
    "EmulatorMismatchError",
    "Estimate",
    "FeatureSpec",
    "GDError",
    "GDTracker",
    "LoopMetrics",
    "MissingExtraError",
    "ObservationModel",
    "ReplayResult",
    "ReplaySettings",
    "FaultInjector",
    "SensorFault",
    "SensorLimits",
    "Simplex",
    "SimplexRun",
    "TrackerSettings",
    "bcr_settings_for",
    "block_features",
    "check_emulator",
    "check_likelihood",
    "clustered_mean",
    "detection_delays",
    "edge_counts",
    "emulator_feature",
    "emulator_noise_std",
    "emulator_vehicle",
    "fast_on_rough_m",
    "gd_errors",
    "interval_coverage",
    "pooled_rmse",
    "record_run",
    "replay_bag",
    "run_closed_loop",
    "shipped_emulator",
    "shipped_emulator_path",
    "window_feature",
]
