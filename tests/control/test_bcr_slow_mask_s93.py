"""The window methods' slow mask (`BCR._window_signal_reason`): a sample below half the top
speed of the samples the checks read is slow, and a dead stretch that takes one in is no fault
(session 93, the two survivors of the last quarter's mutation testing: ``>=`` and
``MAX_SPEED_CHANGE * max``). Exact cases on the doubles of control_doubles.py."""

import numpy as np
import pytest
from control_doubles import FakeCalibrator
from test_bcr_third_quarter_s93 import _gd400

import control
from control import BCR

DEAD = "dead sensor: samples 107-112 span less than 0.001 of the block's standard deviation"


def _dead_stretch_at(speed):
    """One update of 1,000 samples at 1.5 m/s over GD 400 into a paper-window BCR, with samples
    950-955 dead (1e-4 m/s^2 apart, against 0.001 of the block's sd of about 5.8 m/s^2) and
    driven at ``speed``; the estimate's (status, reason). The checks read the newest
    max(125 + 32, 125) = 157 samples (843-999): the dead stretch is their samples 107-112."""
    t, p, a, v = _gd400(1000)
    a, v = a.copy(), v.copy()
    a[950:956] = a[950] + 1e-4 * np.arange(6)
    v[950:956] = speed
    est = BCR(FakeCalibrator(), method="window", feature=control.PAPER_WINDOW).update(t, p, a, v)
    return est.status, est.reason


@pytest.mark.parametrize(
    ("speed", "expected"),
    [
        (1.5, ("sensor_fault", DEAD + "; buffer restarted")),  # at the top speed
        (0.75, ("sensor_fault", DEAD + "; buffer restarted")),  # 0.75 >= 0.5 * 1.5: not slow
        (0.7499, ("ok", "")),  # below 0.75: slow, the dead stretch is passed over
    ],
)
def test_a_dead_stretch_at_exactly_half_the_top_speed_is_at_speed(speed, expected):
    # the mask is ~(|v| >= 0.5 * max|v|), max|v| = 1.5: a sample at exactly 0.75 m/s (0.5 * 1.5
    # is exact in binary) is at speed, so its dead stretch is a fault (with > it would be slow)
    assert _dead_stretch_at(speed) == expected


def test_a_dead_stretch_at_a_third_of_the_top_speed_is_slow():
    # 0.5 m/s against a top speed of 1.5: below 0.5 * 1.5 = 0.75, slow (a robot getting under
    # way): its dead stretch is no fault and the window is "ok". (0.5 / 1.5 = 1/3 would take
    # 0.5 m/s for at speed and flag the stretch.) The window's mean speed,
    # (994 * 1.5 + 6 * 0.5) / 1000 = 1.494 m/s, lies in the emulator's [0.5, 2]
    assert _dead_stretch_at(0.5) == ("ok", "")
