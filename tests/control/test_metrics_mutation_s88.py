"""Mutation testing of control.metrics (s88): hand-computed answers on tiny hand-built traces
that pin what the mutants of the metrics changed unseen: where a track ends when it has no
``length_m`` (its last segment's length), the 1e-9 tolerance at its ends, which estimates count
at a segment boundary, an estimate exactly at the midpoint of a GD change (no crossing), and
"faster than" / "exceeds" as strict inequalities in `fast_on_rough_m`."""

from types import SimpleNamespace

import numpy as np
import pytest

from control import (
    ControlError,
    clustered_mean,
    detection_delays,
    fast_on_rough_m,
    gd_errors,
    pooled_rmse,
)


def track(*segments, start=0.0, length_m=None):
    """What the metrics read of a roadgen Track; no ``length_m`` unless given."""
    starts = start + np.cumsum([0.0] + [float(length) for length, _ in segments[:-1]])
    fields = {"segments": tuple(segments), "boundaries_m": tuple(float(s) for s in starts)}
    if length_m is not None:
        fields["length_m"] = length_m
    return SimpleNamespace(**fields)


def on_track(tr, position) -> bool:
    """Whether gd_errors takes ``position`` (one estimate of 300) as on ``tr``."""
    try:
        gd_errors(tr, [position], [300.0])
    except ControlError as exc:
        assert "off the track" in str(exc)
        return False
    return True


# ----- where the track ends: its last segment's length, or length_m where that is longer -----

SHORT_LAST = track((60.0, 300.0), (40.0, 500.0))  # spans [0, 100] m, no length_m


def test_without_length_m_the_track_ends_at_its_last_segments_end():
    """100 m, not 60 + 60 (the first segment's length) nor 60 (no last length)."""
    assert on_track(SHORT_LAST, 100.0) and on_track(SHORT_LAST, 99.0)
    assert not on_track(SHORT_LAST, 100.001)
    assert not on_track(SHORT_LAST, 119.0)


def test_the_end_is_the_longer_of_length_m_and_the_segments_total():
    """`roadgen.Track.gd_at` reads past the segments up to length_m, and the other way round."""
    longer = track((60.0, 300.0), (40.0, 500.0), length_m=130.0)
    assert on_track(longer, 130.0) and not on_track(longer, 130.001)
    shorter = track((60.0, 300.0), (40.0, 500.0), length_m=80.0)
    assert on_track(shorter, 100.0) and not on_track(shorter, 100.001)
    infinite = track((60.0, 300.0), (40.0, 500.0), length_m=np.inf)  # not a length: ignored
    assert on_track(infinite, 100.0) and not on_track(infinite, 100.001)


@pytest.mark.parametrize(
    "last, end",
    [
        (None, 60.0),  # not a number: no length, the track ends at the last start
        ("abc", 60.0),
        (-5.0, 60.0),  # negative: no length
        (-0.5, 60.0),
        (np.inf, 60.0),  # not finite: no length
        (0.0, 60.0),
        (0.5, 60.5),  # a last segment shorter than a metre counts
        (40.0, 100.0),
    ],
)
def test_a_last_segment_length_that_is_no_length_adds_nothing(last, end):
    tr = track((60.0, 300.0), (last, 500.0))
    assert on_track(tr, end)
    assert not on_track(tr, end + 0.25)


def test_the_tolerance_at_the_ends_is_1e_9_of_the_span_inclusive():
    """Track [10, 110] m: span 100 m, tolerance 1e-7 m, ends included (<=, >=)."""
    tr = track((60.0, 300.0), (40.0, 500.0), start=10.0)
    tol = 1e-9 * 100.0
    assert on_track(tr, 110.0 + 0.5 * tol) and on_track(tr, 10.0 - 0.5 * tol)
    assert on_track(tr, 110.0 + tol) and on_track(tr, 10.0 - tol)  # exactly at: on
    assert not on_track(tr, 110.0 + 1.1 * tol) and not on_track(tr, 10.0 - 1.1 * tol)
    assert not on_track(tr, 9.0) and not on_track(tr, 111.0)


def test_a_track_shorter_than_a_metre_has_a_tolerance_of_1e_9_m():
    tr = track((0.25, 300.0), (0.25, 500.0))  # spans [0, 0.5] m: tolerance 1e-9 x max(0.5, 1)
    assert on_track(tr, 0.5 + 0.8e-9) and on_track(tr, -0.8e-9)
    assert not on_track(tr, 0.5 + 1.5e-9) and not on_track(tr, -1.5e-9)


def test_the_positions_are_checked_whatever_their_estimate():
    """One position off the track among finite ones is refused, not only when all are off."""
    tr = track((60.0, 300.0), (40.0, 500.0), length_m=100.0)
    with pytest.raises(ControlError, match=r"^position holds 150 m at index 1: "):
        gd_errors(tr, [10.0, 150.0, 20.0], [300.0, np.nan, 300.0])


# ----- RMSE per part, by hand -----

TRACK3 = track((10.0, 300.0), (10.0, 500.0), (10.0, 300.0), (10.0, 400.0), length_m=40.0)


def test_rmse_per_part_of_ten_estimates_by_hand():
    """Ten estimates; one exactly on each boundary (it belongs to the segment that starts
    there), one NaN (left out). Parts: GD 300 = segments 0 and 2, 500 = 1, 400 = 3."""
    position = np.array([0.0, 5.0, 10.0, 15.0, 19.999, 20.0, 25.0, 30.0, 35.0, 40.0])
    estimate = np.array([310.0, 280.0, 450.0, 520.0, np.nan, 330.0, 300.0, 390.0, 420.0, 400.0])
    errs = gd_errors(TRACK3, position, estimate)
    assert [e.gd for e in errs] == [300.0, 400.0, 500.0]  # in increasing GD
    by_gd = {e.gd: e for e in errs}
    # GD 300: 0 m (310), 5 m (280), 20 m (330, on the boundary), 25 m (300)
    assert by_gd[300.0].n == 4 and by_gd[300.0].sse == 100.0 + 400.0 + 900.0 + 0.0
    assert by_gd[300.0].rmse == np.sqrt(1400.0 / 4)
    # GD 500: 10 m (450, on the boundary), 15 m (520); 19.999 m is NaN
    assert by_gd[500.0].n == 2 and by_gd[500.0].sse == 2500.0 + 400.0
    assert by_gd[500.0].rmse == np.sqrt(2900.0 / 2)
    # GD 400: 30 m (390, on the boundary), 35 m (420), 40 m (400, the track's end)
    assert by_gd[400.0].n == 3 and by_gd[400.0].sse == 100.0 + 400.0 + 0.0
    assert by_gd[400.0].rmse == np.sqrt(500.0 / 3)
    # pooled over two runs: all estimates together, not a mean of the runs' RMSEs
    other = gd_errors(TRACK3, [12.0], [600.0])
    assert pooled_rmse([errs, other], 500.0) == np.sqrt((2900.0 + 10000.0) / 3)
    assert pooled_rmse([errs, other], 400.0) == np.sqrt(500.0 / 3)


def test_an_estimate_just_before_a_boundary_counts_in_the_part_before():
    errs = {e.gd: e for e in gd_errors(TRACK3, [9.999, 10.0], [300.0, 300.0])}
    assert (errs[300.0].n, errs[300.0].sse) == (1, 0.0)
    assert (errs[500.0].n, errs[500.0].sse) == (1, 40000.0)


# ----- clustered mean, by hand -----


def test_clustered_mean_of_three_runs_by_hand():
    """Runs [1, 2], [6], [3, 3, 3]: mean 18 / 6 = 3; sums minus mean x size: 3 - 6, 6 - 3,
    9 - 9 -> sqrt(9 + 9 + 0) / 6 x sqrt(3 / 2)."""
    mean, se = clustered_mean([[1.0, 2.0], [6.0], [3.0, 3.0, 3.0]])
    assert mean == 3.0
    assert se == pytest.approx(np.sqrt(18.0) / 6.0 * np.sqrt(1.5), rel=1e-15)


# ----- detection delay, by hand -----

RISE_FALL = track((20.0, 300.0), (20.0, 500.0), (20.0, 300.0), length_m=60.0)


def test_an_estimate_exactly_at_the_midpoint_has_not_crossed_it():
    """Midpoint of 300 and 500: 400. A rise is detected by the first estimate above 400, a fall
    by the first below it; 400 itself is no crossing."""
    position = np.arange(0.0, 60.0, 1.0)
    estimate = np.full(position.size, 300.0)
    estimate[(position >= 23) & (position < 26)] = 400.0  # at the midpoint: not yet
    estimate[(position >= 26) & (position < 44)] = 400.5  # 6 m past the rise at 20 m
    estimate[(position >= 44) & (position < 47)] = 400.0  # at the midpoint: not yet
    # from 47 m on: 300, 7 m past the fall at 40 m
    assert detection_delays(RISE_FALL, position, estimate) == (6.0, 7.0)


def test_the_delay_counts_the_first_crossing_in_time_not_in_position():
    """The vehicle reverses: the first estimate above 400 in time is at 28 m, not 24 m."""
    position = np.array([5.0, 21.0, 28.0, 24.0, 45.0])
    estimate = np.array([300.0, 300.0, 450.0, 450.0, 350.0])
    assert detection_delays(RISE_FALL, position, estimate) == (8.0, 5.0)


# ----- fast on rough ground, by hand -----

ROUGH = track((10.0, 300.0), (10.0, 450.0), (10.0, 500.0), length_m=30.0)


def test_fast_on_rough_is_strictly_faster_on_strictly_rougher_ground():
    """gd_max 450: the GD-450 segment is not rough (GD must exceed gd_max); only [20, 30] m is.
    v_safe 1, tol 0.5: a step's mean speed of exactly 1.5 is not faster."""
    position = np.arange(0.0, 30.5, 1.0)  # 0, 1, ..., 30
    speed = np.full(position.size, 2.0)
    speed[25:] = 1.5  # steps from 25 m on have mean speed 1.5 (the 24-25 m step 1.75)
    assert fast_on_rough_m(ROUGH, position, speed, gd_max=450.0, v_safe=1.0, tol=0.5) == 5.0
    assert fast_on_rough_m(ROUGH, position, speed, gd_max=449.0, v_safe=1.0, tol=0.5) == 15.0


@pytest.mark.parametrize("speed, metres", [(1.03, 10.0), (1.01, 0.0), (1.02, 0.0)])
def test_fast_on_rough_takes_a_default_tolerance_of_0_02_m_per_s(speed, metres):
    position = np.arange(0.0, 30.5, 1.0)
    speeds = np.full(position.size, speed)
    assert fast_on_rough_m(ROUGH, position, speeds, gd_max=450.0, v_safe=1.0) == metres


@pytest.mark.parametrize(
    "position, metres",
    [
        ([21.0, 24.5], 3.5),  # two samples: one step, all on rough ground
        ([15.0, 21.0, 24.5], 3.5),  # the step 15-21 m has its midpoint (18 m) on GD 450
        ([21.0], 0.0),
        ([], 0.0),
    ],
)
def test_fast_on_rough_of_two_or_three_samples(position, metres):
    speed = np.full(len(position), 2.0)
    assert fast_on_rough_m(ROUGH, position, speed, gd_max=450.0, v_safe=1.0) == metres
