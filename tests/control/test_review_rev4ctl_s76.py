"""Review of session 76's control messages (rev4): a value just past a bound is printed with the
digits that tell it from the bound, and so must the bound be. Before, the bound was printed
with ``:g`` (6 digits) beside the value's extra digits, so a bound of more than 6 significant
digits read on the wrong side: "GD 349.999991 > GD_max 350" (GD_max 349.99999), "speed
2.0000002 m/s outside the emulator's [0.5, 2]" (the domain's top 2.0000001)."""

import numpy as np
import pytest
from control_doubles import FakeBlockModel, FakeCalibrator, stream
from scipy.stats import chi2

from control import BCR, PAPER_WINDOW, Estimate, Simplex


def const(gd):
    return lambda s: np.full_like(s, gd)


def test_a_gd_past_a_many_digit_gd_max_reads_past_it():
    gd = 349.999991
    est = Estimate(1.0, 1.0, "ok", gd_mean=gd, gd_sd=10.0, interval=(gd - 5, gd + 5))
    command = Simplex(gd_max=349.99999).command(est)
    assert command.reason == "GD 349.999991 > GD_max 349.99999"  # before: "GD_max 350"
    ordinary = Estimate(1.0, 1.0, "ok", gd_mean=400.0, gd_sd=10.0, interval=(395.0, 405.0))
    assert Simplex().command(ordinary).reason == "GD 400 > GD_max 350"


def test_a_speed_past_a_many_digit_domain_top_reads_past_it():
    top, speed = 2.0000001, 2.0000002
    bcr = BCR(FakeBlockModel(v_range=(0.5, top)))
    t, p, a, v = stream(const(400), speed, 3, seed=1)
    ests = [bcr.update(t[k : k + 42], p[k : k + 42], a[k : k + 42], v[k : k + 42])
            for k in range(0, t.size, 42)]  # fmt: skip
    reason = ests[-1].reason
    assert "speed 2.0000002 m/s outside the emulator's [0.5, 2.0000001]" in reason, reason


def test_a_window_p_below_a_many_digit_plausibility_p_reads_below_it():
    limit = 1.2345678e-6
    p = limit * (1 - 1e-6)
    cal = FakeCalibrator()
    cal.emulator.predict = lambda v, gd: (np.zeros((gd.size, 1)), np.ones((gd.size, 1)))
    bcr = BCR(cal, method="window", feature=PAPER_WINDOW, plausibility_p=limit)
    why, got = bcr._window_implausible(1.5, float(np.sqrt(chi2.isf(p, 1))))
    assert got < limit
    assert why.endswith("(p = 1.234566565e-06 < 1.2345678e-06)"), why  # before: "< 1.23457e-06"


@pytest.mark.parametrize("limit", [1e-6, 0.05])
def test_ordinary_limits_read_as_before(limit):
    cal = FakeCalibrator()
    cal.emulator.predict = lambda v, gd: (np.zeros((gd.size, 1)), np.ones((gd.size, 1)))
    bcr = BCR(cal, method="window", feature=PAPER_WINDOW, plausibility_p=limit)
    why, _ = bcr._window_implausible(1.5, 40.0)
    assert why.endswith(f"< {limit:g})")
