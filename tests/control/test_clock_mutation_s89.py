"""Exact cases for `control.robot.clock` that session 89's mutation testing found unchecked:
`stamp_order`'s window edge, `into_gaps`' gap, half-period and block rules, `_overfilled`,
`_move_to_free_slots`, `_phase_step`, `_cut_phase`, `restamp`'s runs and notes, and
`header_skew`'s values. Times on binary fractions (periods of 1 s or 1/128 s) so that every
expectation is exact."""

import numpy as np
import pytest

from control.robot import clock

P = 1 / 128  # s: exact in binary


def _gaps(ts: list[float]) -> tuple[list[int], int]:
    """`into_gaps` of times in received order (period 1 s), each late message left behind."""
    t = np.asarray(ts, dtype=float)
    order = clock.stamp_order(t, 0.0)
    got, moved = clock.into_gaps(t, order, 1.0)
    return got.tolist(), moved


def test_the_documented_constants():
    assert clock.REORDER_PERIODS == 3.0 and clock.RESTAMP_MAX_JITTER == 1 / 6
    assert clock.RESTAMP_MIN_RUN == 256 and clock.RESTAMP_SPLIT_PERIODS == 16.0
    assert clock.RESTAMP_EXACT_S == 1e-6 and clock.RESTAMP_MOVE_PERIODS == 0.75
    assert clock.RESTAMP_STEP_PERIODS == 0.25 and clock.SKEW_BIN_S == 1.0


def test_stamp_order_sorts_a_step_back_of_exactly_its_window_and_takes_a_list():
    assert clock.stamp_order([0.0, 1.0, 0.5], 0.5).tolist() == [0, 2, 1]
    assert clock.stamp_order([0.0, 1.0, 0.5], 0.25).tolist() == [0, 1, 2]  # a clock step
    assert clock.stamp_order([1.0, 0.0], 2.0).tolist() == [1, 0]  # two messages
    assert clock.stamp_order([3.0], 2.0).tolist() == [0]


def test_a_gap_of_exactly_one_and_a_half_periods_takes_no_late_message():
    assert _gaps([0, 1, 2.5, 3.5, 1.75]) == ([0, 1, 2, 3, 4], 0)


@pytest.mark.parametrize("late, moves", [(1.5, True), (3.5, True), (1.4, False), (3.6, False)])
def test_a_late_message_fills_a_gap_from_half_a_period_off_either_end(late, moves):
    expected = ([0, 1, 4, 2, 3], 1) if moves else ([0, 1, 2, 3, 4], 0)
    assert _gaps([0, 1, 4, 5, late]) == expected


def test_two_messages_in_order_are_enough_to_fill_the_gap_between_them():
    assert _gaps([0, 3, 1]) == ([0, 2, 1], 1)


def test_a_block_with_a_message_that_fits_nowhere_stays_behind_and_frees_its_gap():
    # 2.5 and 0.5 were left behind together; 0.5 fits no gap, so 2.5 stays and 3.5 moves alone
    assert _gaps([0, 1, 2, 4, 5, 6, 2.5, 0.5, 7, 3.5, 8]) == ([0, 1, 2, 9, 3, 4, 5, 6, 7, 8, 10], 1)


def test_a_block_whose_one_message_overfills_its_gap_stays_behind_whole():
    # 3.0 and 7.0 together; 3.0 and 3.2 overfill the gap (2, 4): 7.0 stays with 3.0
    assert _gaps([0, 1, 2, 4, 5, 6, 8, 9, 3.0, 7.0, 10, 3.2, 11]) == (list(range(13)), 0)


def test_messages_left_behind_in_reverse_fill_their_gap_in_time_order():
    assert _gaps([0, 1, 2, 5, 6, 4, 3, 7]) == ([0, 1, 2, 6, 5, 3, 4, 7], 2)


def test_more_late_messages_than_the_gap_s_missing_slots_all_stay_behind():
    assert _gaps([0, 1, 2, 4, 5, 2.5, 6, 3.5, 7]) == (list(range(9)), 0)


def test_two_late_messages_in_one_gap_half_a_period_apart_both_move_closer_neither():
    assert _gaps([0, 1, 2, 5, 6, 2.75, 7, 3.25, 8]) == ([0, 1, 2, 5, 7, 3, 4, 6, 8], 2)
    assert _gaps([0, 1, 2, 5, 6, 2.8, 7, 3.2, 8]) == (list(range(9)), 0)


def test_two_gaps_each_take_their_own_late_messages():
    t = [0, 1, 2, 5, 6, 7, 10, 11, 3, 4, 8, 9]
    assert _gaps(t) == ([0, 1, 2, 8, 9, 3, 4, 5, 10, 11, 6, 7], 4)


def _move(k: list[float], r: list[float]) -> tuple[list[float], list[float], int]:
    """`_move_to_free_slots` with period 1: (slots, offsets, moved)."""
    ka, ra = np.asarray(k, dtype=float), np.asarray(r, dtype=float)
    moved = clock._move_to_free_slots(ka, ra, 1.0)
    return ka.tolist(), ra.tolist(), moved


def test_the_later_of_two_messages_on_one_slot_moves_to_a_free_slot_after_it():
    assert _move([0, 1, 1, 3], [0, 0.1, 0.5, 0]) == ([0, 1, 2, 3], [0, 0.1, -0.5, 0], 1)
    assert _move([0, 1, 1], [0, 0, 0.5]) == ([0, 1, 2], [0, 0, -0.5], 1)  # the last slot
    # nearer the slot it has than the free one, but the slot before is taken: it moves
    assert _move([0, 1, 1, 3], [0, -0.5, 0.3, 0]) == ([0, 1, 2, 3], [0, -0.5, -0.7, 0], 1)


def test_the_earlier_of_two_messages_on_one_slot_moves_to_a_free_slot_before_it():
    assert _move([0, 2, 2, 3], [0, -0.5, 0.1, 0]) == ([0, 1, 2, 3], [0, 0.5, 0.1, 0], 1)
    assert _move([0, 2, 2, 3], [0, -0.25, 0.1, 0]) == ([0, 1, 2, 3], [0, 0.75, 0.1, 0], 1)
    assert _move([1, 1, 3], [-0.5, 0.1, 0]) == ([0, 1, 3], [0.5, 0.1, 0], 1)  # the first slot


def test_with_both_neighbours_free_a_tie_at_the_limit_moves_the_later_message_on():
    assert _move([0, 2, 2, 4], [0, -0.25, 0.25, 0]) == ([0, 2, 3, 4], [0, -0.25, -0.75, 0], 1)
    assert _move([0, 2, 2, 4], [0, -0.3, 0.4, 0]) == ([0, 2, 3, 4], [0, -0.3, -0.6, 0], 1)


def test_nothing_moves_without_a_free_neighbour_or_for_a_duplicate():
    assert _move([0, 1, 1, 2], [0, 0, 0.5, 0]) == ([0, 1, 1, 2], [0, 0, 0.5, 0], 0)
    assert _move([0, 1, 1, 2], [0, -0.5, 0.5, 0]) == ([0, 1, 1, 2], [0, -0.5, 0.5, 0], 0)
    assert _move([0, 1, 1, 3], [0, 0.3, 0.3, 0]) == ([0, 1, 1, 3], [0, 0.3, 0.3, 0], 0)


def test_phase_step_finds_a_step_in_three_blocks_and_not_one_of_a_quarter_period():
    step = np.r_[np.zeros(60), np.full(36, 0.5)]
    assert clock._phase_step(step, 1.0) == 60
    assert clock._phase_step(step[:95], 1.0) == 0  # fewer than three blocks of 32
    assert clock._phase_step(np.r_[np.zeros(60), np.full(36, 0.25)], 1.0) == 0


def test_phase_step_places_the_step_within_its_96_offsets_only():
    r = np.r_[np.zeros(100), np.full(100, 0.5)]
    assert clock._phase_step(r, 1.0) == 100
    r[128] = 1000.0  # the first offset past the 96 (32-127) that hold the step
    assert clock._phase_step(r, 1.0) == 100


def test_cut_phase_of_exact_stamps_lies_opposite_the_emptiest_bins():
    k = np.arange(100)
    assert clock._cut_phase(0.5 + k * P, 0.5, P) == 0.5 + P / 64  # on the clock
    assert clock._cut_phase((k + 0.25) * P, 0.0, P) == P * 8.5 / 32  # a quarter late
    assert clock._cut_phase((k + 0.5) * P, 0.0, P) == -P * 15.5 / 32  # half a period off


def test_a_run_of_exactly_the_shortest_length_is_restamped():
    rng = np.random.default_rng(1)
    new, info = clock.restamp(np.arange(256) * P + rng.normal(0, 0.05 * P, 256))
    assert info.restamped and info.runs == 1
    assert np.allclose(np.diff(new), np.diff(new)[0], rtol=0, atol=1e-12)


def test_runs_too_short_are_kept_and_counted_in_the_note():
    t = np.r_[np.arange(200), 300 + np.arange(200)] * P
    new, info = clock.restamp(list(t))  # (a list is taken too)
    assert new.tolist() == t.tolist() and info == clock.Restamping(False)
    assert info.runs == 0 and info.moved == 0
    t = np.r_[np.arange(300), 317.5 + np.arange(100)] * P
    t[50] += 0.625 * P
    new, info = clock.restamp(t)
    assert info.restamped and info.runs == 1
    assert info.note.endswith("; 100 message(s) in runs too short to fit kept as recorded")
    assert np.array_equal(new[300:], t[300:])


def test_a_pause_longer_than_sixteen_periods_splits_the_stamps_into_two_runs():
    for pause, runs in [(16, 1), (17, 2), (18.5, 2)]:
        t = np.r_[np.arange(300), 299 + pause + np.arange(300)] * P
        new, info = clock.restamp(t)
        assert (info.runs, info.restamped, info.jitter_max_s) == (runs, False, 0.0), pause
        assert np.array_equal(new, t)


def test_the_rate_is_the_longest_run_s_and_two_runs_are_named():
    t = np.r_[np.arange(400) * P, 420 * P + np.arange(300) / 100]
    new, info = clock.restamp(t)
    assert info.restamped and info.runs == 2 and info.rate_hz == 128.0
    assert "re-stamped on a 128.00 Hz clock (2 runs, split at pauses and clock steps)" in info.note


def test_a_late_message_on_a_taken_slot_moves_back_to_the_free_one_and_is_counted():
    rng = np.random.default_rng(3)
    g = np.arange(400) * P
    t = g + rng.normal(0, 0.04 * P, 400)
    t[100] = g[100] + 0.6 * P
    new, info = clock.restamp(t)
    assert info.restamped and info.moved == 1 and info.runs == 1
    assert "; 1 late or early message(s) moved to a free neighbouring slot" in info.note
    assert np.allclose(np.diff(new), 1 / info.rate_hz, rtol=0, atol=1e-9)


T0 = 1_700_000_000_300_000_000  # ns: not on a whole second


def test_header_skew_is_the_median_per_second_of_the_imu_s_offset_less_the_odometry_s():
    ol = T0 + np.arange(4) * 1_000_000_000
    os_ = ol - np.array([5, 7, 9, 11]) * 1_000_000  # odometry offset -5 ms - 2 ms per s
    il = T0 + np.array([0, 250, 500, 1000, 1500, 2000]) * 1_000_000
    ioff = np.array([1, 2, 9, 3, 5, 4]) * 1_000_000  # stamp - receive time, ns
    skew = clock.header_skew(il + ioff, il, os_, ol)
    # per message: ioff + 5 ms + 2 ms per s of receive time
    each = np.array([1 + 5, 2 + 5.5, 9 + 6, 3 + 7, 5 + 8, 4 + 9]) / 1e3
    want = np.r_[np.full(3, each[1]), np.full(2, (each[3] + each[4]) / 2), each[5]]
    np.testing.assert_allclose(skew, want, rtol=0, atol=1e-15)


def test_header_skew_needs_half_its_messages_distinct_in_receive_time():
    ol = T0 + np.arange(4) * 1_000_000_000
    il = T0 + np.array([0, 0, 500, 500, 1000, 1000]) * 1_000_000_000 // 1000
    assert clock.header_skew(il, il, ol, ol) is not None  # 3 distinct of 6
    il2 = T0 + np.array([0, 0, 0, 500, 500, 500]) * 1_000_000
    assert clock.header_skew(il2, il2, ol, ol) is None  # 2 of 6
    il3 = T0 + np.array([0, 0, 500, 500]) * 1_000_000
    assert clock.header_skew(il3, il3, ol, ol) is not None  # 2 of 4
    one = np.full(4, T0)
    assert clock.header_skew(il3, il3, one, one) is None  # one distinct: never


def test_a_late_message_alone_in_its_gap_moves_while_a_close_pair_in_another_stays():
    # gap (2, 4): 3.0 (its own block); gap (6, 10): 7.0 and 7.4 too close, 8.5 with them
    t = [0, 1, 2, 4, 5, 6, 10, 3.0, 11, 7.0, 7.4, 8.5, 12]
    assert _gaps(t) == ([0, 1, 2, 7, 3, 4, 5, 6, 8, 9, 10, 11, 12], 1)


def test_cut_phase_of_stamps_spread_evenly_over_the_period_is_half_a_period_on():
    t = np.arange(64) * P * (1 + 1 / 32)  # two stamps in each of the 32 phase bins
    assert clock._cut_phase(t, 0.0, P) == P / 2


def test_stamps_all_alike_are_not_restamped():
    t = np.zeros(300)
    new, info = clock.restamp(t)
    assert new is not None and np.array_equal(new, t) and info == clock.Restamping(False)
