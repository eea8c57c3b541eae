"""Review of the short level check (session 71): with a known noise sd its flight exemption is
blind to the signal's offset and sign, as the other checks are (docs/robot.md: with emulator B
"neither the offset nor the sign changes the statuses").

It exempted a stretch whose mean lies near -g itself; a real IMU's flights read about 0 with
gravity kept (the replay's default) and +g with the axis' sign flipped. Of 138,000 clean
simulated blocks with N(0, 1) noise (1,200 campaign drives of 120 s, seeds 24-35) none
was flagged as recorded and 2 with +9.81 added or the sign flipped ("signal level drops": 8
samples of a flight at 1/22,198 of the rest's variance, 24 at 1/400.2; campaign seed 24, drive
14, block 25; seed 33, drive 90, block 63).
"""

import numpy as np
import pytest

from control.sensor_checks import SensorLimits, short_level_drop, signal_fault

NOISY = SensorLimits(noise_sd_mps2=1.0)


def _flight_block(seed: int = 71) -> np.ndarray:
    """A loud block with a wheel in the air for 24 samples (0.2 s), gravity removed: the flight
    reads -g with the sensor's N(0, 1) noise, at 1/500 of the rest's variance."""
    rng = np.random.default_rng(seed)
    a = 30.0 * rng.standard_normal(125)
    a[60:84] = -9.81 + rng.standard_normal(24)
    return a


def test_with_a_known_noise_sd_offset_and_sign_leave_the_short_level_check_alone():
    a = _flight_block()
    assert signal_fault(a, NOISY) == ""
    for moved in (a + 9.81, -a, 9.81 - a, a - 0.45):  # gravity kept, a flipped axis, both
        assert signal_fault(moved, NOISY) == ""
    free = short_level_drop(a, 24, anchored=False)
    for moved in (a + 9.81, -a):
        ratio, start = short_level_drop(moved, 24, anchored=False)
        assert start == free[1] and ratio == pytest.approx(free[0], rel=1e-12)
    dropped = a.copy()
    dropped[20:44] *= 0.01  # a gain that drops is still seen, wherever the level lies
    for moved in (dropped, dropped + 9.81, -dropped):
        assert "signal level drops" in signal_fault(moved, NOISY)


def test_without_a_noise_sd_the_exemption_stays_at_free_fall_itself():
    a = _flight_block()
    assert signal_fault(a, SensorLimits()) == ""
    assert short_level_drop(a, 24)[0] < 10  # the flight exempt at -g
    assert short_level_drop(-a, 24)[0] > 400  # +g is no flight where the level is known
    assert short_level_drop(-a, 24, anchored=False)[0] < 10
