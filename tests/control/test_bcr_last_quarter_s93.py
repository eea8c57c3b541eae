"""Mutation testing of control/bcr.py (session 93, every 4th site from the third: 2, 6, ...,
874): exact cases on the doubles of control_doubles.py (each test's numbers are worked by hand
in its comments)."""

import dataclasses
import math

import numpy as np
import pytest
from control_doubles import FakeBlockModel
from scipy.special import ndtr, ndtri
from test_bcr_quarter_s93 import _LoudBy
from test_bcr_third_quarter_s93 import _feed, _gd400, _Scored

import control
from control import BCR


def test_bcr_settings_are_frozen():
    # settings are shared by copies and restored BCRs (`BCR.__deepcopy__` keeps them): a field
    # cannot be set after the checks ran
    settings = control.BCRSettings()
    with pytest.raises(dataclasses.FrozenInstanceError):
        settings.method = "window"
    assert settings.method == "changepoint"


def test_a_new_single_phase_bcrs_filter_is_its_one_phases():
    # update_every 125 = the block: one phase. Before any estimate (and after reset) `filter`
    # is phase 0's, the only one
    bcr = BCR(FakeBlockModel(), update_every=125)
    assert len(bcr._phases) == 1
    assert bcr.filter is bcr._phases[0].filter
    bcr.reset()
    assert bcr.filter is bcr._phases[0].filter


def test_a_call_without_samples_names_the_silence_not_the_last_fault():
    # 125 samples stuck at 0: "stuck sensor". A call of no samples 5 s later names the
    # silence alone (5.00 s > 0.5 s): the stuck block came with an earlier call
    t, p, a, v = _gd400(125)
    bcr = BCR(FakeBlockModel(), update_every=125)
    est = bcr.update(t, p, 0.0 * a, v)
    assert est.status == "sensor_fault" and est.reason.startswith("stuck sensor: 125 identical")
    est = bcr.update(t[:0], p[:0], a[:0], v[:0], now=float(t[-1]) + 5.0)
    assert (est.status, est.reason) == (
        "sensor_fault",
        "no samples for 5.00 s (max_silence_s = 0.5)",
    )


def test_a_clock_step_back_moves_a_phases_data_time_without_an_undo():
    # one phase: blocks 1 and 2 ok (data times 125/120 and 250/120 s); block 3 stuck: it undoes
    # block 2 (data time back to 125/120) and clears the undo; block 4's stamps step back 100 s
    # (a fault: skipped, nothing to undo). The phase's data time moves back with the clock:
    # 125/120 - 100 = -98.958 s, not 1.042 s (data newer than the estimate's time, -95.83 s)
    t, p, a, v = _gd400(500)
    a, t = a.copy(), t.copy()
    a[250:375] = 0.0
    t[375:] -= 100.0
    ests = _feed(BCR(FakeBlockModel(), update_every=125), t, p, a, v)
    assert [e.status for e in ests] == ["ok", "ok", "sensor_fault", "sensor_fault"]
    assert ests[2].data_time == 125 / 120
    assert "(the sample clock stepped back 100 s); block skipped" in ests[3].reason
    assert math.isclose(ests[3].data_time, 125 / 120 - 100.0, abs_tol=1e-9)
    assert math.isclose(ests[3].time, 500 / 120 - 100.0, abs_tol=1e-9)


def test_a_standing_block_of_zero_acceleration_reads_out_of_the_speed_range():
    # a robot at rest whose accelerometer reads exactly 0 (no noise): its standing block's
    # band powers are log 0 = -inf, so the frozen-odometry check has no level score and says
    # nothing; the block is out of the emulator's speeds
    t = np.arange(1, 126) / 120
    zero = np.zeros(125)
    bcr = BCR(FakeBlockModel(), update_every=125)
    for k in range(2):
        est = bcr.update(t + k * 125 / 120, zero + 3.0, zero, zero)
        assert (est.status, est.reason) == (
            "out_of_domain",
            "speed 0 m/s outside the emulator's [0.5, 2]",
        )


def test_a_hold_ends_where_the_blocks_since_read_release_p_exactly():
    # level scores -6 (p = ndtr(-6) = 9.9e-10 < 1e-6: flagged, a hold begins), then +2: the
    # two read -4 / sqrt(2) = -2.83 sd (no flag), and the block since the hold reads z = 2,
    # p = ndtr(2). With release_p = ndtr(2) the hold ends ("ok": p >= release_p); one ulp
    # above, it holds
    t, p, a, v = _gd400(250)
    release = float(ndtr(2.0))
    for release_p, status in ((release, "ok"), (np.nextafter(release, 1.0), "implausible")):
        bcr = BCR(_Scored([-6.0, 2.0]), update_every=125, release_p=release_p)
        ests = _feed(bcr, t, p, a, v)
        assert ests[0].status == "implausible" and "read quieter" in ests[0].reason
        assert ests[1].status == status
    assert ests[1].reason.startswith("held since the implausible estimate at 1.04 s: the blocks")


def test_the_g_slip_is_named_within_a_factor_2_of_1_over_standard_gravity():
    # the g slip's factor is 1 / 9.80665 = 0.10197: gain 0.19 lies within a factor 2 of it
    # (0.19 / 0.10197 = 1.86 < 2), gain 0.21 not (2.06); both are a gain clause (<= 1/3)
    t, p, a, v = _gd400(125)
    est = BCR(_LoudBy(0.19), update_every=125).update(t, p, a, v)
    assert est.reason.endswith(
        "smoothest ground's acceleration times 0.19: if every block reads so, acceleration in "
        "g? accel must be m/s^2 (g x 9.80665); or the wrong axis (one that feels little of "
        "the ground)"
    )
    est = BCR(_LoudBy(0.21), update_every=125).update(t, p, a, v)
    assert est.reason.endswith(
        "its band powers read as the smoothest ground's acceleration times 0.21"
    )


def test_a_first_scan_probability_equal_to_plausibility_p_still_scans():
    # level scores 4, then -6: the two read -2 / sqrt(2) sd, p = ndtr(-2 / sqrt(2)) = 0.079.
    # With plausibility_p that very number the sum is not flagged (p >= limit), and the scan
    # runs: the newest alone reads -6 sd, flagged
    t, p, a, v = _gd400(250)
    limit = float(ndtr(sum([4.0, -6.0]) / (np.sqrt(2) * 1.0)))
    ests = _feed(BCR(_Scored([4.0, -6.0]), update_every=125, plausibility_p=limit), t, p, a, v)
    assert ests[0].status == "ok"
    assert ests[1].status == "implausible"
    assert ests[1].reason.startswith("the last 1 block(s) read quieter")


def test_an_estimate_exactly_max_age_s_old_is_not_stale():
    # one block: data time 125/120 s; a call without samples at now = that + 5 s (max_age_s,
    # and within max_silence_s = 10): 5 s old exactly is fresh; one ulp later, stale
    t, p, a, v = _gd400(125)
    bcr = BCR(FakeBlockModel(), update_every=125, max_silence_s=10.0)
    data_time = bcr.update(t, p, a, v).data_time
    now = data_time + 5.0
    assert now - data_time == 5.0
    assert bcr.update(t[:0], p[:0], a[:0], v[:0], now=now).status == "ok"
    est = bcr.update(t[:0], p[:0], a[:0], v[:0], now=np.nextafter(now, 10.0))
    assert est.status == "stale"


def test_a_standing_block_scoring_exactly_the_limit_reads_as_driving():
    # standing speeds, a level score of ndtri(1e-6) = -4.75 sd exactly (sd 1): "no quieter
    # than driving" holds at the limit (z >= limit): the frozen-odometry clause (out_of_domain
    # before STANDING_SETTLE_S); a score one ulp lower is a robot at rest
    n = 125
    t, zero = np.arange(1, n + 1) / 120, np.zeros(n)
    accel = np.random.default_rng(1).standard_normal(n) * 0.3
    limit = float(ndtri(1e-6))
    est = BCR(_Scored([limit]), update_every=125).update(t, zero + 3.0, accel, zero)
    assert est.status == "out_of_domain"
    assert "(level score -4.75 sd, a sensor at rest reads below -4.75)" in est.reason
    lower = np.nextafter(limit, -10.0)
    est = BCR(_Scored([lower]), update_every=125).update(t, zero + 3.0, accel, zero)
    assert (est.status, est.reason) == (
        "out_of_domain",
        "speed 0 m/s outside the emulator's [0.5, 2]",
    )


def test_a_change_point_block_runs_the_timing_checks():
    # a block at 1.5 m/s whose position jumps 5 m at sample 60: over the block (124 steps of
    # 1/120 s) it moved 124 * 1.5 / 120 + 5 = 6.55 m, its speeds give 1.55 m
    t, p, a, v = _gd400(125)
    p = p.copy()
    p[60:] += 5.0
    est = BCR(FakeBlockModel(), update_every=125).update(t, p, a, v)
    assert (est.status, est.reason) == (
        "sensor_fault",
        "odometry disagrees with the speeds: the position moved 6.55 m over the block, its "
        "speeds give 1.55 m",
    )
