"""The window methods' dead-stretch check over new samples in which the robot starts or stops:
only the stretches that take in a slow sample (below half the samples' top speed) pass."""

import numpy as np
from _robot_cases import start_from_rest

import control
from control.sensor_checks import SensorLimits, signal_fault


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
    t, position, accel, speed = start_from_rest(bcr.settings.samples_per_update)
    _dead(accel, 36, accel.size)
    estimate = bcr.update(t, position, accel, speed)
    assert estimate.status == "sensor_fault" and "dead sensor" in estimate.reason, estimate.reason


def test_only_a_dead_stretch_that_takes_in_a_slow_sample_passes():
    _, _, accel, speed = start_from_rest(125)
    slow = speed < 0.5 * speed.max()  # samples 0 and 1
    assert "dead sensor: samples 0-5" in signal_fault(accel, SensorLimits())
    assert signal_fault(accel, SensorLimits(), steady=False, slow=slow) == ""  # the start
    _dead(accel, 60, 70)  # dead from sample 59 (the value it holds) at full speed: a fault
    assert "dead sensor: samples 59-64" in signal_fault(
        accel, SensorLimits(), steady=False, slow=slow
    )
    slow[64:] = True  # the robot slowing to rest from sample 64: every dead stretch takes it in
    assert signal_fault(accel, SensorLimits(), steady=False, slow=slow) == ""
