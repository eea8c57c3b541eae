"""Small inputs shared by the robot I/O tests: a short drive's messages, a start from rest and a
closed-loop result that needs no simulation."""

import numpy as np

from control.closed_loop import ClosedLoopResult


def short_drive(n: int = 60):
    """(imu time s, accel m/s^2, odometry time s, position m, speed m/s) of n samples at 120 Hz."""
    t = 1.0 + np.arange(n) / 120.0
    return t, np.random.default_rng(0).normal(size=n), t, 0.5 * (t - 1.0), np.full(n, 0.5)


def start_from_rest(n: int, seed: int = 0) -> tuple[np.ndarray, ...]:
    """(t, position, accel, speed) of ``n`` samples at 120 Hz of a robot getting under way at
    20 m/s^2 to 1 m/s over a road that starts flat (roadgen's lead-in): its first samples read
    an all but constant acceleration (noise-free, case A), then ~4 m/s^2 of ground."""
    t = np.arange(1, n + 1) / 120.0
    speed = np.minimum(20.0 * t, 1.0)
    position = np.cumsum(speed) / 120.0
    accel = np.random.default_rng(seed).normal(0.0, 4.0, n)
    accel[:6] = [1.6e-4, 5.1e-4, 1.07e-3, 2.85e-3, 3.9e-3, 2.63e-3]  # a closed-loop run's start
    return t, position, accel, speed


def small_result(n: int = 240, settings: dict | None = None) -> ClosedLoopResult:
    """A small closed-loop result of n samples (no drive needed to record one)."""
    t = np.arange(n) / 120.0
    te = t[41::42]
    k = te.size
    return ClosedLoopResult(
        time=te, position=0.5 * te, gd_mean=np.full(k, 300.0), gd_lo=np.full(k, 250.0),
        gd_hi=np.full(k, 350.0), gd_true=np.full(k, 300.0), status=np.array(["ok"] * k),
        reason=np.array([""] * k), domain_edge=np.array([""] * k), prob_change=np.zeros(k),
        command=np.ones(k), mode=np.array(["performance"] * k), latency_s=np.zeros(k),
        sample_time=t, sample_position=0.5 * t, sample_speed=np.full(n, 0.5),
        sample_accel=np.random.default_rng(0).normal(size=n), metrics={},
        settings={} if settings is None else settings,
    )  # fmt: skip
