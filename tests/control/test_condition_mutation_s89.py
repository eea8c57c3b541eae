"""Exact cases for `control.robot.condition` that session 89's (sampled) mutation testing found
unchecked: `nominal_period`'s edges, defaults of a report, names and rates in messages."""

import numpy as np
import pytest

from control.errors import BagError
from control.robot import condition


def test_the_documented_constants():
    assert condition.GAP_PERIODS == 1.5 and condition.SPLIT_STEPS == 16.0
    assert condition.HEAVY_JITTER_STEPS == 0.35 and condition.MAX_LOWPASS_TAPS == 200_001


def test_the_nominal_period_leaves_repeated_stamps_and_a_pause_out():
    assert condition.nominal_period([0.0, 0.0, 1.0, 1.0, 2.0, 2.0, 3.0]) == 1.0
    assert condition.nominal_period(np.r_[np.arange(10.0), 14.0 + np.arange(10.0)]) == 1.0


def test_heavy_jitter_takes_a_step_of_exactly_sixteen_median_steps_into_the_mean():
    steps = np.r_[np.tile([0.25, 0.5, 1.0, 2.25], 10), 16.0]  # median step 1, robust sd 1.1
    t = np.concatenate([[0.0], np.cumsum(steps)])
    assert condition.nominal_period(t) == 56 / 41
    assert condition.nominal_period(t[:-1]) == 1.0  # without it: the mean of the cycle


def test_increasing_and_to_rate_take_lists():
    assert condition.increasing([0.0, 2.0, 1.0, 3.0]).tolist() == [True, True, False, True]
    t, a, info = condition.to_rate([0.0, 0.5, 1.0], [1.0, 2.0, 3.0], 2.0)
    assert t.tolist() == [0.0, 0.5, 1.0] and a.tolist() == [1.0, 2.0, 3.0]


def test_an_imu_used_as_recorded_reports_no_filter_and_a_clean_stream_no_gap():
    _, _, info = condition.to_rate(np.arange(300) / 120, np.zeros(300), 120.0)
    assert (info.resampled, info.method, info.up, info.down, info.taps) == (False, "", 1, 1, 0)
    assert (info.runs, info.dropped, info.trimmed_per_edge) == (0, 0, 0)
    report = condition.check_stream("/imu", np.arange(50) / 120, np.ones(50, bool), "header")
    assert report.largest_gap_s == 0.0 and report.clean


def test_a_message_without_a_topic_names_the_imu_topic_alone():
    with pytest.raises(BagError, match="^the IMU topic has fewer than two distinct time stamps$"):
        condition.to_rate(np.zeros(3), np.zeros(3), 120.0)


def test_a_rate_that_differs_in_four_digits_is_given_in_four():
    assert condition._rate_text(100.04, 120.0) == "100"
    assert condition._rate_text(119.98, 120.0) == "119.98"
