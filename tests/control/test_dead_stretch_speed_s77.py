"""The window methods' dead-stretch check over new samples in which the robot starts or stops:
only the stretches that take in a slow sample (below half the samples' top speed) pass."""

import numpy as np

import control
from control.sensor_checks import SensorLimits, signal_fault

RATE_HZ = 120.0


def _start_from_rest(n: int, seed: int = 0) -> tuple[np.ndarray, ...]:
    """(t, position, accel, speed) of ``n`` samples of a robot getting under way at 20 m/s^2 to
    1 m/s: its first samples read an all but constant acceleration, then ~4 m/s^2 of ground."""
    t = np.arange(1, n + 1) / RATE_HZ
    speed = np.minimum(20.0 * t, 1.0)
    position = np.cumsum(speed) / RATE_HZ
    accel = np.random.default_rng(seed).normal(0.0, 4.0, n)
    accel[:6] = [1.6e-4, 5.1e-4, 1.07e-3, 2.85e-3, 3.9e-3, 2.63e-3]  # a closed-loop run's start
    return t, position, accel, speed


def _dead(accel: np.ndarray, start: int, stop: int) -> np.ndarray:
    """``accel`` dead over [start, stop): its value there held, with 1e-3 m/s^2 of jitter."""
    jitter = np.random.default_rng(1).normal(0.0, 1e-3, stop - start)
    accel[start:stop] = accel[start - 1] + jitter
    return accel


def test_a_sensor_that_dies_just_after_a_start_is_a_dead_sensor_for_the_window_method():
    # Before: the whole update in which the robot started skipped the dead-stretch check, and a
    # sensor dead from 0.3 s gave ok estimates on dead data (GD falling, a smoother road than
    # the real one) until the window's variance left the emulator's range, ~9 m later.
    bcr = control.BCR.from_emulator(control.shipped_emulator("A", "window"), method="window")
    t, position, accel, speed = _start_from_rest(bcr.settings.samples_per_update)
    _dead(accel, 36, accel.size)
    estimate = bcr.update(t, position, accel, speed)
    assert estimate.status == "sensor_fault" and "dead sensor" in estimate.reason, estimate.reason


def test_only_a_dead_stretch_that_takes_in_a_slow_sample_passes():
    _, _, accel, speed = _start_from_rest(125)
    slow = speed < 0.5 * speed.max()  # samples 0 and 1
    assert "dead sensor: samples 0-5" in signal_fault(accel, SensorLimits())
    assert signal_fault(accel, SensorLimits(), steady=False, slow=slow) == ""  # the start
    _dead(accel, 60, 70)  # dead from sample 59 (the value it holds) at full speed: a fault
    assert "dead sensor: samples 59-64" in signal_fault(
        accel, SensorLimits(), steady=False, slow=slow
    )
    slow[64:] = True  # the robot slowing to rest from sample 64: every dead stretch takes it in
    assert signal_fault(accel, SensorLimits(), steady=False, slow=slow) == ""
