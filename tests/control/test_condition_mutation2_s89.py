"""Exact cases for `control.robot.condition` that session 89's mutation testing (its second part:
the rest of `to_rate`, `gravity_direction`, `highpass`, `static_level_marks`, `path_length`,
`integrated_speed`, `odometry_at`, and the filter's design numbers) found unchecked.

The resampled cases use a constant signal at 2 Hz taken to 1 Hz: every output value is then the
constant exactly and every output time a whole or half second, so the expectations are written
out by hand (up 1, down 2; the filter's half-length, 20 samples at 2 Hz, is 10 output samples).
"""

import numpy as np
import pytest

from control.errors import BagError
from control.robot import condition

RUN = np.arange(61) / 2  # 0 .. 30 s at 2 Hz: output at 1 Hz from 10 to 20 s after the trim


def _at_1_hz(t: np.ndarray, a: np.ndarray, method: str = "sample"):
    return condition.to_rate(t, a, 1.0, method=method)


def test_the_ratio_keeps_its_denominator_at_most_100_below_100_times_the_rate():
    assert condition._ratio(242.4, 120.0) == (49, 99)  # 50/101 is nearer, but 101 > 100
    assert condition._ratio(10_000.0, 1.0) == (1, 10_000)


def test_the_sample_filter_is_kaisers_60_db_design_with_its_cut_off_at_045_of_the_input():
    from scipy.signal import firwin

    up, down, fir = condition.resampling_filter(2.0, 1.0, "sample")
    # width 0.1 * 2 Hz over the 1 Hz Nyquist = 0.2; taps: ceil((60 - 7.95) / (2.285 pi 0.2)) + 1
    # = 38, made odd: 39; beta 0.1102 (60 - 8.7)
    assert (up, down, fir.size) == (1, 2, 39)
    want = firwin(39, 0.9, window=("kaiser", 0.1102 * (60.0 - 8.7)), fs=2.0)
    assert np.array_equal(fir, want)


def test_the_lowpass_filter_is_resample_polys_own():
    from scipy.signal import firwin

    up, down, fir = condition.resampling_filter(2.0, 1.0, "lowpass")
    assert (up, down) == (1, 2)
    assert np.array_equal(fir, firwin(41, 0.5, window=("kaiser", 5.0)))


def test_the_longest_lowpass_filter_is_made_and_one_longer_is_refused():
    assert condition.resampling_filter(10_000.0, 1.0, "lowpass")[2].size == 200_001
    with pytest.raises(BagError, match="a filter of 200021 taps, above MAX_LOWPASS_TAPS"):
        condition.resampling_filter(10_001.0, 1.0, "lowpass")


def test_a_rate_exactly_at_the_tolerance_is_used_as_recorded():
    t = np.arange(10.0)  # 1 Hz against 0.8 Hz: 1 / 0.8 - 1 = 0.25 exactly
    _, _, info = condition.to_rate(t, np.zeros(10), 0.8, tolerance=0.25)
    assert not info.resampled
    _, _, info = condition.to_rate(t, np.zeros(10), 0.8, tolerance=0.25 - 1e-9)
    assert info.resampled


@pytest.mark.parametrize(("method", "taps"), [("sample", 39), ("lowpass", 41)])
def test_a_clean_run_is_trimmed_by_the_filters_half_length_in_output_samples(method, taps):
    t, a, info = _at_1_hz(RUN, np.full(61, 3.0), method)
    assert (info.up, info.down, info.taps, info.trimmed_per_edge) == (1, 2, taps, 10)
    assert (info.runs, info.dropped) == (1, 0)
    assert t.tolist() == list(range(10, 21)) and a.tolist() == [3.0] * 11


def test_a_run_after_a_non_finite_value_starts_with_a_nan_one_period_after_the_last_sample():
    t, a, info = _at_1_hz(np.r_[RUN, 30.5, 32 + RUN], np.r_[np.ones(61), np.nan, np.ones(61)])
    assert (info.runs, info.dropped) == (2, 1)
    assert t.tolist() == [*range(10, 22), *range(42, 53)]
    assert np.array_equal(a, np.r_[np.ones(11), np.nan, np.ones(11)], equal_nan=True)


def test_a_run_after_a_repeated_stamp_starts_with_the_last_sample_again():
    t, a, info = _at_1_hz(np.r_[RUN, 30.0, 31.5 + RUN], np.ones(123))
    assert (info.runs, info.dropped) == (2, 1)
    assert t.tolist() == [*range(10, 21), 20, *(41.5 + np.arange(11))]
    assert a.tolist() == [1.0] * 23


def test_each_fault_between_two_runs_gives_its_own_marker_even_around_a_run_too_short():
    # a NaN, one good sample (a run too short to resample), a repeated stamp: a NaN at 21 s for
    # the NaN, then that marker again (21 s, NaN) for the repeated stamp
    t = np.r_[RUN, 30.5, 31.0, 31.0, 31.5 + RUN]
    a = np.r_[np.ones(61), np.nan, 1.0, 1.0, np.ones(61)]
    t2, a2, info = _at_1_hz(t, a)
    assert (info.runs, info.dropped) == (2, 2)
    assert t2.tolist() == [*range(10, 22), 21, *(41.5 + np.arange(11))]
    assert np.array_equal(a2, np.r_[np.ones(11), np.nan, np.nan, np.ones(11)], equal_nan=True)


def test_a_step_of_one_and_a_half_output_periods_is_no_gap_a_longer_one_is_without_a_marker():
    t, a, info = _at_1_hz(np.r_[RUN, 31.5 + RUN], np.ones(122))  # 1.5 s: one run
    assert info.runs == 1 and t.tolist() == list(range(10, 52)) and a.tolist() == [1.0] * 42
    t, a, info = _at_1_hz(np.r_[RUN, 32 + RUN], np.ones(122))  # 2 s: a gap, no sample between
    assert info.runs == 2 and t.tolist() == [*range(10, 21), *range(42, 53)]


def test_resampling_a_run_later_by_a_whole_number_of_seconds_shifts_it_bit_for_bit():
    a = np.sin(1.3 * RUN) + RUN % 3
    t0, a0, _ = _at_1_hz(RUN, a)
    t1, a1, _ = _at_1_hz(64.0 + RUN, a)
    assert t0.tolist() == list(range(10, 21))
    assert np.array_equal(t1, t0 + 64.0) and np.array_equal(a1, a0)


@pytest.mark.parametrize("method", ["sample", "lowpass"])
def test_an_imu_without_a_finite_value_resamples_to_nothing(method):
    # (raised IndexError: the first run's start was set in an empty mask)
    t, a, info = _at_1_hz(np.arange(5) / 2, np.full(5, np.nan), method)
    assert t.size == 0 and a.size == 0
    assert (info.resampled, info.runs, info.dropped) == (True, 0, 5)


def test_a_replay_of_a_fast_imu_without_a_finite_value_says_it_gives_no_sample(
    emulator_a, tmp_path
):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    from control.robot import replay_bag, write_sensor_bag

    t = np.arange(480) / 240.0  # 2 s at 240 Hz, every value NaN
    o = slice(None, None, 6)
    bag = write_sensor_bag(
        tmp_path / "nan", t, np.full(t.size, np.nan), t[o], 1.5 * t[o], np.full(t[o].size, 1.5)
    )
    with pytest.raises(BagError, match="gives no sample at 120 Hz.* 480 of its 480 messages"):
        replay_bag(bag, emulator_a)


@pytest.mark.parametrize(("n", "want"), [(41, []), (42, [10.0])])
def test_a_run_must_span_more_than_twice_the_trim_to_give_a_sample(n, want):
    # as the replay says when nothing is left: runs "longer than 2 trim / rate_hz s" (20 s)
    t, _, info = _at_1_hz(np.arange(n) / 2, np.ones(n))
    assert t.tolist() == want and info.runs == len(want)


def test_a_run_taken_up_by_three_quarters_keeps_the_samples_inside_it():
    # 4 Hz to 3 Hz: up 3, down 4; the "sample" filter at 12 Hz: width 0.1 * 4 / 6, taps
    # ceil(52.05 / (2.285 pi 0.4 / 6)) + 1 = 110, made odd: 111; trim ceil(55 / 4) = 14.
    # 102 samples span 25.25 s: 77 output samples, 76 of them at or before 25.25 s (k / 3)
    t, a, info = condition.to_rate(np.arange(102) / 4, np.full(102, 2.0), 3.0)
    assert (info.up, info.down, info.taps, info.trimmed_per_edge) == (3, 4, 111, 14)
    assert np.array_equal(t, np.arange(14, 62) / 3) and a.tolist() == [2.0] * 48


def test_the_filter_text_names_each_method():
    _, _, info = _at_1_hz(RUN, np.ones(61), "lowpass")
    assert info.filter == (
        "the IMU's 2 Hz to 1 Hz: linear interpolation onto a uniform 2 Hz grid per contiguous "
        "run (removes stamp jitter), then scipy.signal.resample_poly(up=1, down=2) with a "
        "41-tap Kaiser-window FIR, zero-phase: anti-aliasing low-pass (cut-off 0.5 Hz); 10 "
        "samples cut at each end of each run"
    )
    _, _, info = _at_1_hz(RUN, np.ones(61), "sample")
    assert "39-tap Kaiser-window FIR, zero-phase: band-limited interpolation (cut-off 0.9 Hz:" in (
        info.filter
    )


# gravity_direction -------------------------------------------------------------------------

G = condition.GRAVITY


def _gravity(mean, static_mps2=9.8):
    return condition.gravity_direction(
        np.array([mean], dtype=float), "z", 1.0, "/imu", None, "highpass", static_mps2
    )


def test_the_gravity_band_holds_half_to_one_and_a_half_g_both_included():
    assert condition.GRAVITY_BAND == (0.5, 1.5) and condition.MAX_TILT_DEG == 10.0
    assert _gravity([0.0, 0.0, 0.5 * G]) == "" and _gravity([0.0, 0.0, 1.5 * G]) == ""
    for level in (0.25 * G, 1.6 * G):
        assert _gravity([0.0, 0.0, level]).startswith(
            "static_mps2 = 9.8 m/s^2, but the IMU topic '/imu' reads no gravity"
        )
    assert _gravity([0.0, 0.0, 0.25 * G], None) == ""  # no level given: nothing to say


def test_gravity_along_another_axis_gives_its_angle_past_ninety_degrees():
    # (9, 0, -3): z read as up lies arccos(-3 / sqrt(90)) = 108.4 degrees from gravity
    said = _gravity([9.0, 0.0, -3.0])
    assert "gravity lies along its x axis, 108 degrees from the z axis read as up" in said
    assert "imu_axis='x', imu_sign=+1 (--axis x --sign 1)" in said


# highpass ----------------------------------------------------------------------------------


def _hp(x):
    from scipy.signal import butter, sosfiltfilt

    return sosfiltfilt(butter(2, 0.1, btype="highpass", fs=2.0, output="sos"), x)


def test_a_clean_run_is_filtered_whole_steps_of_half_and_one_and_a_half_periods_included():
    a = np.sin(np.arange(20.0)) + 3.0
    assert np.array_equal(condition.highpass(np.arange(20) / 2, a, 2.0, 0.1), _hp(a))
    t = np.r_[np.arange(10) / 2, 4.75, 5.5 + np.arange(9) / 2]  # steps 0.25 s, 0.75 s
    assert np.array_equal(condition.highpass(t, a, 2.0, 0.1), _hp(a))
    t = np.r_[np.arange(10) / 2, 5.3 + np.arange(10) / 2]  # 0.8 s: 1.6 periods, a break
    assert np.array_equal(condition.highpass(t, a, 2.0, 0.1), np.r_[_hp(a[:10]), _hp(a[10:])])


def test_a_non_finite_value_ends_a_run_and_a_run_of_nine_has_its_mean_removed():
    # 9 samples are too few for the filter's padding (3 (2 sections + 1) = 9): the mean goes
    a = np.r_[np.sin(np.arange(10.0)), np.nan, np.cos(np.arange(9.0))] + 3.0
    out = condition.highpass(np.arange(20) / 2, a, 2.0, 0.1)
    assert np.array_equal(out[:10], _hp(a[:10])) and np.isnan(out[10])
    assert np.array_equal(out[11:], a[11:] - a[11:].mean())


def test_non_finite_values_in_a_row_leave_no_empty_run_to_average(recwarn):
    a = np.r_[np.ones(10), np.nan, np.nan, np.ones(10)]
    out = condition.highpass(np.arange(22) / 2, a, 2.0, 0.1)
    assert np.isnan(out[10:12]).all() and np.isfinite(np.delete(out, [10, 11])).all()
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


# static_level_marks ------------------------------------------------------------------------


def _limits(span):
    from control.sensor_checks import SensorLimits

    return SensorLimits(static_mps2=9.8, static_span=span)


def test_every_update_from_the_first_full_block_to_the_last_sample_is_checked():
    from control.sensor_checks import static_level

    marks = condition.static_level_marks(np.zeros(250), _limits(0), 125, 125, np.arange(250.0), 1)
    why = static_level(0.0, 125, _limits(0)) + " (the signal before the high-pass)"
    assert marks == {124: why, 249: why}


def test_a_span_fault_where_the_block_is_off_too_keeps_the_blocks_reason():
    from control.sensor_checks import static_level

    limits = _limits(250)
    marks = condition.static_level_marks(np.zeros(250), limits, 125, 125, np.arange(250.0), 1)
    assert marks[249] == static_level(0.0, 125, limits) + " (the signal before the high-pass)"


def test_a_span_as_long_as_the_recording_and_a_step_of_half_a_period_are_checked():
    from control.sensor_checks import static_span_level

    limits = _limits(8)
    why = static_span_level(0.0, limits) + " (the signal before the high-pass)"
    t = np.r_[np.arange(4.0), 3.5, 4.5, 5.5, 6.5]  # a step of half a period: kept
    assert condition.static_level_marks(np.zeros(8), limits, 8, 100, t, 1.0) == {7: why}
    # a break just after the first span leaves it whole; the second span starts at the break
    t = np.r_[np.arange(8.0), 10.0 + np.arange(8.0)]
    marks = condition.static_level_marks(np.zeros(16), limits, 8, 100, t, 1.0)
    assert marks == {7: why, 15: why}


# path_length, integrated_speed, odometry_at ------------------------------------------------


def test_a_turn_between_long_steps_starts_a_new_piece():
    # 3 m along x, then 5 m along (4, 3): a turn of 36.9 degrees, the path 8 m (not the chord)
    assert condition.path_length([[3.0, 0.0, 0.0], [7.0, 3.0, 0.0]]).tolist() == [3.0, 8.0]


def test_the_integrated_speed_starts_at_zero_and_sums_trapezoids():
    assert condition.integrated_speed([0.0, 1.0, 3.0], [1.0, 3.0, 5.0]).tolist() == [0, 2, 10]
    assert condition.integrated_speed([], []).size == 0


def test_odometry_at_its_ends_in_its_first_step_and_from_one_message():
    t_odom = np.array([0.0, 1.0, 1.25])  # a gap of 1 s first, then 0.25 s
    pos, spd = condition.odometry_at(
        [0.0, 0.5, 1.125, 1.25], t_odom, [0.0, 2.0, 3.0], [4, 4, 8], 0.5
    )
    assert np.array_equal(pos, [np.nan, np.nan, 2.5, 3.0], equal_nan=True)
    assert np.array_equal(spd, [np.nan, np.nan, 6.0, 8.0], equal_nan=True)
    pos, spd = condition.odometry_at([1.0, 2.0], np.array([1.0]), [5.0], [2.0], 0.1)
    assert np.array_equal(pos, [5.0, np.nan], equal_nan=True)
    assert np.array_equal(spd, [2.0, np.nan], equal_nan=True)


def test_markers_at_2_hz_repeat_the_last_sample_or_follow_it_by_half_a_second():
    # 4 Hz to 2 Hz: runs of 0 .. 15 s give 5 .. 10 s by half seconds (trim 10)
    run = np.arange(61) / 4
    a = np.sin(run) + run
    t2, a2, _ = condition.to_rate(np.r_[run, 15.0, 15.25 + run], np.r_[a, 0.0, a], 2.0)
    assert t2[10:12].tolist() == [10.0, 10.0] and a2[11] == a2[10] != a2[0]
    t2, a2, _ = condition.to_rate(np.r_[run, 15.25, 15.5 + run], np.r_[a, np.nan, a], 2.0)
    assert t2[10:12].tolist() == [10.0, 10.5] and np.isnan(a2[11])
