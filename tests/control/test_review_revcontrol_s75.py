"""Review of the static-level check (session 75): the replay's marks before the high-pass and
the BCR's long span (`StaticSpan`) with a wild sample and with chunks longer than the span."""

import warnings

import numpy as np

from control.robot.condition import static_level_marks
from control.sensor_checks import SensorLimits, StaticSpan

G = 9.80665
ON = SensorLimits(static_mps2=G)
BLOCK_ONLY = SensorLimits(static_mps2=G, static_span=0)


def _healthy(n: int, seed: int = 1) -> np.ndarray:
    """A healthy up axis: gravity plus a gravity-free stand-in for a drive (m/s^2)."""
    return np.random.default_rng(seed).normal(0.0, 2.0, n) + G


def test_one_wild_raw_sample_marks_only_the_updates_that_hold_it():
    n = 120 * 60
    t = np.arange(n) / 120.0
    for wild in (1e20, 1.7e308):
        raw = _healthy(n)
        raw[100] = wild
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # (no overflow warning either)
            block = static_level_marks(raw, BLOCK_ONLY, 42, 125, t, 120.0)
            both = static_level_marks(raw, ON, 42, 125, t, 120.0)
        # was: every update of the minute (169), the running sum's rounding carried on
        assert block and max(block) < 100 + 125
        assert both and max(both) < 100 + 1000 + 42


def test_a_wild_value_in_the_bcr_span_is_a_fault_without_a_warning(new_bcr):
    n = 120 * 12
    t, accel = np.arange(n) / 120.0, _healthy(n)
    accel[1200:1202] = 1.7e308  # finite: out of range (sensor_fault), summed in the span
    bcr = new_bcr("B", sensor=ON)
    statuses = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # was: RuntimeWarning overflow in StaticSpan.push
        for k in range(0, n - 41, 42):
            s = slice(k, k + 42)
            statuses.append(bcr.update(t[s], 1.5 * t[s], accel[s], np.full(42, 1.5)).status)
    assert statuses[1218 // 42] == "sensor_fault"


def test_the_span_keeps_stream_order_with_chunks_longer_than_it():
    a = _healthy(733, seed=3)
    means = []
    for cuts in ([30], list(range(7, 733, 7)), [5, 400, 520]):  # chunks of 703, 7, 395 ...
        span = StaticSpan(100)
        for part in np.split(a, cuts):
            span.push(part)
        means.append(span.mean())
    assert means[0] == means[1] == means[2]  # the ring's order is the stream's: bit for bit
