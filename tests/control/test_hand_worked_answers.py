"""Answers worked out by hand: detection delays over parts made of several segments of one GD,
estimates that are not finite or on a boundary; which Simplex laws a fault can make faster."""

from types import SimpleNamespace

import numpy as np
import pytest

from control import Estimate, Simplex, detection_delays, gd_errors


def hand_track(*segments: tuple[float, float]) -> SimpleNamespace:
    """A track with just what the metrics read: segments, their starts and the length, m."""
    starts = np.cumsum([0.0] + [length for length, _ in segments[:-1]])
    return SimpleNamespace(
        segments=tuple(segments),
        boundaries_m=tuple(float(s) for s in starts),
        length_m=float(sum(length for length, _ in segments)),
    )


def test_a_rough_part_split_into_segments_of_one_gd_is_one_part_for_the_delay():
    """300 | 500 500 | 300: the rise is detected 30 m in (in the second GD-500 segment), the
    fall 20 m in; splitting a part must not turn a late detection into 'never'."""
    split = hand_track((50.0, 300.0), (25.0, 500.0), (25.0, 500.0), (50.0, 300.0))
    whole = hand_track((50.0, 300.0), (50.0, 500.0), (50.0, 300.0))
    position = np.arange(0.0, 150.0, 1.0)
    estimate = np.where((position >= 80) & (position < 120), 500.0, 300.0)
    assert detection_delays(split, position, estimate) == pytest.approx((30.0, 20.0))
    assert detection_delays(whole, position, estimate) == pytest.approx((30.0, 20.0))


def test_an_estimate_that_is_not_finite_detects_nothing_as_it_scores_nothing():
    """gd_errors leaves an infinite estimate out (no estimate); the delay must too."""
    track = hand_track((50.0, 300.0), (50.0, 500.0))
    position = np.array([50.0, 52.0, 55.0])
    estimate = np.array([np.inf, np.nan, 480.0])
    assert detection_delays(track, position, estimate) == pytest.approx((5.0,))
    assert gd_errors(track, position, estimate)[1].n == 1
    falling = hand_track((50.0, 500.0), (50.0, 300.0))
    assert detection_delays(falling, position, np.array([-np.inf, 450.0, 320.0])) == (5.0,)


def test_an_estimate_on_a_boundary_belongs_to_the_part_that_starts_there():
    track = hand_track((50.0, 300.0), (50.0, 500.0))
    errors = gd_errors(track, [50.0], [480.0])
    assert (errors[0].n, errors[1].n, errors[1].sse) == (0, 1, 400.0)
    assert detection_delays(track, [49.0, 50.0], [480.0, 480.0]) == (0.0,)


@pytest.mark.parametrize("law", ["linear", "switch", "paper"])
def test_only_the_papers_law_can_be_made_faster_by_a_latched_fault(law):
    """The docstring's guarantee: after a fault the run commands v_safe, never more than the law
    on "linear" and "switch"; "paper" commands less than v_safe above GD 275 (0 from 300)."""
    simplex = Simplex(law=law)
    run = simplex.start()
    run.command(Estimate(1.0, 1.0, "sensor_fault"))
    gds = np.linspace(200.0, 350.0, 151)
    law_speed = np.array([simplex.command(Estimate(2.0, 2.0, "ok", gd_mean=g)).speed for g in gds])
    latched = np.array([run.command(Estimate(2.0, 2.0, "ok", gd_mean=g)).speed for g in gds])
    assert np.all(latched == simplex.v_safe)
    faster = gds[latched > law_speed]
    if law == "paper":
        assert faster.min() == pytest.approx(276.0) and faster.max() == 350.0
    else:
        assert faster.size == 0
