"""What the vehicle's sensors report: the noisy accelerometer and the tyre contact flags."""

from __future__ import annotations

import math

import numpy as np

from vehicle import checks
from vehicle.errors import VehicleError
from vehicle.models import Model
from vehicle.road_input import RoadInput

MAX_NOISE_STD = 1e100
"""Largest accelerometer noise std, m/s^2: far beyond any sensor, and small enough that the
measured samples and their variance over any drive (a campaign's f) stay finite."""


def check_rate(rate_hz: float) -> float:
    """Return the sample rate as a float, or raise VehicleError unless a finite real > 0 whose
    sample period 1 / rate_hz is finite."""
    rate = checks.positive("rate_hz", rate_hz, unit="Hz")
    if not math.isfinite(1.0 / rate):
        raise VehicleError(
            f"rate_hz={rate_hz!r} Hz is out of range: its sample period 1/rate_hz overflows"
        )
    return rate


def check_noise(noise_std: float) -> float:
    """Return the noise standard deviation as a float, or raise VehicleError unless a real in
    [0, ``MAX_NOISE_STD``]."""
    std = checks.non_negative("noise_std", noise_std, unit="m/s^2")
    if std > MAX_NOISE_STD:
        raise VehicleError(
            f"noise_std={noise_std!r} is out of range: allowed [0, {MAX_NOISE_STD:g}] m/s^2 "
            "(vehicle.sensor.MAX_NOISE_STD: far beyond any sensor; from about 1e154 the "
            "measured accelerations' variance, f, overflows)"
        )
    return std


def add_noise(accel: np.ndarray, noise_std: float, rng: np.random.Generator) -> np.ndarray:
    """Measured acceleration: ``accel`` plus N(0, noise_std^2) white noise (a copy if std is 0)."""
    if noise_std == 0.0:
        return accel.copy()
    return accel + rng.normal(0.0, noise_std, size=accel.shape)


def contact_flags(
    model: Model,
    road: RoadInput,
    s_axle: np.ndarray,
    speed: np.ndarray,
    z: np.ndarray,
    zt: np.ndarray,
    axle: int,
) -> np.ndarray:
    """True where the tyre of ``axle`` (0 front, 1 rear) presses on the road (total force > 0).

    Args (each (n,)): s_axle: the axle's road position, m; speed, m/s; z, zt: the axle's vertical
    displacement (m) and velocity (m/s). With bilateral contact (``lift_off=False``) a False flag
    marks where a real tyre would have lost contact.
    """
    if hasattr(model, "axle_stiffness_n_per_m"):
        k, c = model.axle_stiffness_n_per_m, model.axle_damping_ns_per_m
    else:
        k, c = model.tyre_stiffness_n_per_m, model.tyre_damping_ns_per_m
    u, du = road.heights(s_axle), road.slopes(s_axle)
    deviation = -k * (z - u) - c * (zt - speed * du)
    return model.static_tyre_loads_n[axle] + deviation > 0.0
