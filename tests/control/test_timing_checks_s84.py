"""The stream and timing checks at their documented edges (session 84, mutation testing): a
bound is "beyond" (a value on it passes), a two-sample block is checked, the counts of
consecutive chunks add up, and the worst gap is the largest one."""

from __future__ import annotations

import numpy as np
import pytest

from control.sensor_checks import (
    MAX_SPEED_MPS,
    NO_BREAKS,
    STREAM_FIELDS,
    SensorLimits,
    StreamBreaks,
    stream_breaks,
    timing_fault,
)

RATE = 4.0  # a period of 0.25 s: half and one and a half periods are exact in binary
DT = 1.0 / RATE


def _block(n: int, speed: float = 1.0):
    t = np.arange(n) * DT
    return t, speed * t.copy(), np.zeros(n), np.full(n, speed)


def test_a_speed_on_max_speed_is_not_beyond_it():
    t, pos, acc, spd = _block(6, MAX_SPEED_MPS)
    pos[2] = np.nan  # a break elsewhere, so that the whole check runs (not its shortcut)
    drop, restart, breaks = stream_breaks(t, pos, acc, spd, np.nan, RATE)
    assert breaks.too_fast == 0 and breaks.nonfinite == 1
    assert drop.tolist() == [False, False, True, False, False, False]
    assert not restart.any()
    assert timing_fault(t, MAX_SPEED_MPS * t, spd, RATE, SensorLimits()) == ""
    spd_over = spd.copy()
    spd_over[3] = np.nextafter(MAX_SPEED_MPS, np.inf)
    assert "out of range" in timing_fault(t, MAX_SPEED_MPS * t, spd_over, RATE, SensorLimits())


def test_a_step_of_half_a_period_is_not_backwards_and_one_and_a_half_is_no_gap():
    t = np.array([0.0, 0.5 * DT, 2.0 * DT, 3.5 * DT, 4.5 * DT])
    pos, acc, spd = np.zeros(5), np.zeros(5), np.zeros(5)
    acc[4] = np.inf  # a break elsewhere, so that the whole check runs
    drop, restart, breaks = stream_breaks(t, pos, acc, spd, np.nan, RATE)
    assert breaks.backwards == 0 and breaks.worst_gap == 0.0
    assert drop.tolist() == [False, False, False, False, True]
    assert not restart.any()
    # just below half a period: backwards; just above one and a half: a gap
    for t2, backwards, gap in [
        (np.array([0.0, np.nextafter(0.5 * DT, 0.0), 1.5 * DT, 2.5 * DT, 3.5 * DT]), 1, 0.0),
        (np.array([0.0, DT, np.nextafter(2.5 * DT, 1.0), 3.5 * DT, 4.5 * DT]), 0, 1.5 * DT),
    ]:
        drop, restart, breaks = stream_breaks(t2, pos, acc, spd, np.nan, RATE)
        assert breaks.backwards == backwards
        assert breaks.worst_gap == pytest.approx(gap)
        assert drop.tolist() == [False, bool(backwards), False, False, True]
        assert restart.tolist() == [False, False, gap > 0, False, False]


def test_the_worst_gap_is_the_largest_of_several():
    t = np.array([0.0, 1.0, 2.0, 12.0, 13.0]) * DT  # gaps of 10 periods, then none
    t = np.concatenate([t, t[-1] + np.array([4.0, 5.0]) * DT])  # and one of 4
    n = t.size
    _, restart, breaks = stream_breaks(t, np.zeros(n), np.zeros(n), np.zeros(n), np.nan, RATE)
    assert breaks.worst_gap == pytest.approx(10.0 * DT)
    assert restart.sum() == 2


def test_the_breaks_of_consecutive_chunks_add_up_to_those_of_the_chunks_joined():
    a = StreamBreaks(2, ("accel",), 1, 60.0, 3, 0.5)
    b = StreamBreaks(1, ("t", "speed"), 4, 70.0, 1, 2.0)
    s = a + b
    assert (s.nonfinite, s.too_fast, s.backwards) == (3, 5, 4)
    assert (s.fastest, s.worst_gap) == (70.0, 2.0)
    assert s.names == ("t", "accel", "speed")  # STREAM_FIELDS order, each once
    assert s.names == tuple(n for n in STREAM_FIELDS if n in s.names)
    assert b + a == s
    assert a + NO_BREAKS == a and NO_BREAKS + a == a
    # chunked or whole, one stream gives the same breaks
    t = np.array([0.0, 1.0, 1.0, 2.0, 9.0, 10.0, 11.0, 11.0]) * DT
    n = t.size
    spd = np.array([1.0, 1.0, 60.0, 1.0, 1.0, 70.0, 1.0, 1.0])
    pos, acc = np.zeros(n), np.zeros(n)
    pos[1] = np.nan
    whole = stream_breaks(t, pos, acc, spd, np.nan, RATE)[2]
    first = stream_breaks(t[:4], pos[:4], acc[:4], spd[:4], np.nan, RATE)[2]
    second = stream_breaks(t[4:], pos[4:], acc[4:], spd[4:], t[3], RATE)[2]
    assert first + second == whole


def test_a_gap_of_a_thousand_periods_names_milliseconds():
    assert "milliseconds" in StreamBreaks(worst_gap=1000.0 * DT).reason(RATE)
    assert "nanoseconds" in StreamBreaks(worst_gap=1.05e9 * DT).reason(RATE)
    for periods in (3.0, 2000.0):
        assert "time stamps are in" not in StreamBreaks(worst_gap=periods * DT).reason(RATE)


def test_a_block_of_two_samples_is_checked_and_of_one_is_not():
    t = np.array([0.0, 3.0 * DT])  # three periods for one step
    spd = np.array([1.0, 1.0])
    assert "another rate" in timing_fault(t, t.copy(), spd, RATE, SensorLimits())
    assert timing_fault(t[:1], t[:1], spd[:1], RATE, SensorLimits()) == ""


def test_a_span_off_by_exactly_the_rate_tolerance_passes():
    limits = SensorLimits(rate_tolerance=0.25)
    spd = np.zeros(2)
    for span in (1.25 * DT, 0.75 * DT):  # |span / expected - 1| == 0.25 exactly
        t = np.array([0.0, span])
        assert timing_fault(t, np.zeros(2), spd, RATE, limits) == ""
    for span in (np.nextafter(1.25 * DT, 1.0), np.nextafter(0.75 * DT, 0.0)):
        t = np.array([0.0, span])
        assert "another rate" in timing_fault(t, np.zeros(2), spd, RATE, limits)


def test_odometry_off_by_exactly_its_tolerance_plus_slack_passes():
    limits = SensorLimits(odometry_tolerance=0.25, odometry_slack_m=0.25)
    t = np.arange(5) * DT  # speeds of 1 m/s over 1 s: 1 m; allowed off by 0.25 + 0.25 m
    spd = np.ones(5)
    for moved in (1.5, 0.5):
        assert timing_fault(t, np.array([0, 0, 0, 0, moved]), spd, RATE, limits) == ""
    for moved in (1.5 + 1e-9, 0.5 - 1e-9):
        assert "odometry" in timing_fault(t, np.array([0, 0, 0, 0, moved]), spd, RATE, limits)


def test_a_first_stamp_that_is_not_finite_leaves_the_one_before_it_as_the_previous():
    t = np.array([np.nan, 2.0 * DT, 3.0 * DT])  # from t_prev = 0: a step of two periods
    n = t.size
    drop, restart, breaks = stream_breaks(t, np.zeros(n), np.zeros(n), np.zeros(n), 0.0, RATE)
    assert drop.tolist() == [True, False, False]
    assert restart.tolist() == [False, True, False]
    assert breaks.worst_gap == 2.0 * DT and breaks.backwards == 0


def test_speeds_beyond_max_speed_up_to_a_thousand_times_it_ask_for_mm_per_s():
    t = np.arange(3) * DT
    for fastest, hinted in [
        (60.0, True),
        (1e3 * MAX_SPEED_MPS, True),
        (1e3 * MAX_SPEED_MPS + 1, False),
    ]:
        spd = np.array([1.0, fastest, 1.0])
        assert ("mm/s" in timing_fault(t, t.copy(), spd, RATE, SensorLimits())) is hinted
        breaks = stream_breaks(t, t.copy(), np.zeros(3), spd, np.nan, RATE)[2]
        assert ("mm/s" in breaks.reason(RATE)) is hinted


@pytest.mark.parametrize(
    ("ratio", "named"),
    [(1e3, "position in mm"), (1.0 / 3.6, "km/h"), (-1.0, "opposite directions"), (3.0, None)],
)
def test_odometry_off_by_a_unit_slip_names_it(ratio, named):
    t = np.arange(9) * DT  # speeds of 2 m/s over 2 s: 4 m
    spd = np.full(9, 2.0)
    text = timing_fault(t, ratio * 2.0 * t, spd, RATE, SensorLimits())
    assert "odometry disagrees" in text
    if named is None:
        assert "if every block reads so" not in text
    else:
        assert named in text


def test_a_bcr_names_every_break_of_an_update_whatever_its_chunking(block_model):
    from control_doubles import stream

    from control import BCR

    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 4, seed=3)
    a, p = a.copy(), p.copy()
    a[130], a[140], p[170] = np.nan, np.nan, np.nan  # all in the second 125-sample update
    reasons = []
    for chunk in (125, 25, 5):
        bcr = BCR(block_model, update_every=125)
        ests = [
            bcr.update(t[k : k + chunk], p[k : k + chunk], a[k : k + chunk], v[k : k + chunk])
            for k in range(0, 250, chunk)
        ]
        reasons.append(ests[-1].reason)
        assert "3 sample(s) with non-finite position/accel" in ests[-1].reason
    assert reasons[0] == reasons[1] == reasons[2]
