"""The window methods catch a sensor that dies on an update's last samples as soon as one that
dies earlier in an update: their signal checks read each update's new samples with the samples
before them (`control.bcr.CHECK_CONTEXT`)."""

import copy

import numpy as np
import pytest

import control

RATE_HZ = 120.0
SPEED_MPS = 1.5


def _stream(n: int) -> tuple[np.ndarray, ...]:
    """(t, position, accel, speed) of ``n`` samples at a steady 1.5 m/s over ~4 m/s^2 of
    ground."""
    t = np.arange(1, n + 1) / RATE_HZ
    speed = np.full(n, SPEED_MPS)
    return t, SPEED_MPS * t, np.random.default_rng(7).normal(0.0, 4.0, n), speed


def _caught_after_m(bcr: control.BCR, died: int, updates: int = 4) -> float:
    """Distance (m) from a death at sample ``died`` (the sensor holds the value it read before
    it, with 1e-3 m/s^2 of jitter) to the first "sensor_fault"; inf if none in ``updates``
    updates after it."""
    every = bcr.settings.samples_per_update
    t, position, accel, speed = _stream((died // every + updates) * every)
    jitter = np.random.default_rng(died).normal(0.0, 1e-3, accel.size - died)
    accel[died:] = accel[died - 1] + jitter
    for start in range(0, accel.size, every):
        part = slice(start, start + every)
        estimate = bcr.update(t[part], position[part], accel[part], speed[part])
        if start + every > died and estimate.status == "sensor_fault":
            return float(position[start + every - 1] - position[died])
    return float("inf")


@pytest.mark.parametrize("method", ["window", "filter", "tempered"])
def test_a_sensor_dead_from_any_sample_of_an_update_is_caught_within_an_update(method):
    # Before: a sensor that died on an update's last 1-5 samples (or its first, holding the
    # previous update's last value) left the next update all dead: its checks had nothing
    # healthy to read it against, and ok estimates ran on dead data (GD falling) for 5-9 m.
    emulator = control.shipped_emulator("A", "window")
    proto = control.BCR.from_emulator(emulator, method=method)
    every = proto.settings.samples_per_update
    update_m = every / RATE_HZ * SPEED_MPS
    caught = {
        offset: _caught_after_m(copy.deepcopy(proto), 2 * every + offset)
        for offset in (0, 60, every - 5, every - 1)
    }
    assert max(caught.values()) <= update_m + 1e-9, (caught, update_m)
