"""Metrics: RMSE per GD, detection delay, distance fast on rough ground, clustered means."""

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

TRACK = SimpleNamespace(
    segments=((50.0, 300.0), (50.0, 500.0), (50.0, 300.0)),
    boundaries_m=(0.0, 50.0, 100.0),
    length_m=150.0,
)


def test_rmse_is_taken_against_the_gd_at_each_estimate_position():
    pos = np.array([10, 20, 60, 70, 120, 140, 145.0])
    est = np.array([310, 290, 480, 520, 330, np.nan, 300.0])
    errs = {e.gd: e for e in gd_errors(TRACK, pos, est)}
    assert errs[300].n == 4 and errs[500].n == 2  # the NaN (no estimate) is left out
    assert errs[300].rmse == pytest.approx(np.sqrt((100 + 100 + 900 + 0) / 4))
    assert errs[500].rmse == pytest.approx(20.0)
    # Pooling two runs weighs every estimate equally.
    other = gd_errors(TRACK, np.array([70.0]), np.array([440.0]))
    assert pooled_rmse([tuple(errs.values()), other], 500) == pytest.approx(
        np.sqrt((400 + 400 + 3600) / 3)
    )
    # A part without estimates in any run has no RMSE (NaN, as one run's), not an error.
    no_estimates = gd_errors(TRACK, np.array([10.0]), np.array([np.nan]))
    assert np.isnan(pooled_rmse([no_estimates], 300)) and np.isnan(no_estimates[0].rmse)


def test_detection_delay_is_the_distance_to_the_midpoint_crossing():
    pos = np.arange(0, 150, 2.0)
    est = np.where(pos < 57, 300.0, 500.0)
    est[pos >= 110] = 300.0
    assert detection_delays(TRACK, pos, est) == pytest.approx((8.0, 10.0))
    never = np.full(pos.shape, 300.0)
    assert np.isnan(detection_delays(TRACK, pos, never)[0])


def test_fast_on_rough_counts_only_rough_ground_above_v_safe():
    pos = np.linspace(0, 150, 15001)
    speed = np.where(pos < 58, 2.0, 1.0)
    assert fast_on_rough_m(TRACK, pos, speed, gd_max=350, v_safe=1.0) == pytest.approx(
        8.0, abs=0.02
    )
    assert fast_on_rough_m(TRACK, pos, np.full(pos.size, 1.0), 350, 1.0) == 0.0


def test_an_estimate_without_a_position_is_left_out_not_charged_to_the_last_part():
    errs = {e.gd: e for e in gd_errors(TRACK, [np.nan, 5.0], [300.0, 300.0])}
    assert errs[500].n == 0 and errs[300].n == 1 and errs[300].sse == 0.0


@pytest.mark.parametrize(
    "call",
    [
        lambda: gd_errors(TRACK, [1.0, 2.0, 3.0], [300.0, 300.0]),
        lambda: detection_delays(TRACK, [1.0, 12.0, 13.0], [300.0, 500.0]),
        lambda: fast_on_rough_m(TRACK, [1.0, 12.0, 13.0], [2.0, 2.0], 350.0, 1.0),
        lambda: gd_errors(TRACK, ["a", "b"], [300.0, 300.0]),
        lambda: gd_errors(TRACK, ["1.5", "2.5"], [300.0, 300.0]),
        lambda: gd_errors(TRACK, [True, False], [300.0, 300.0]),
        lambda: gd_errors(TRACK, [1.0 + 2j, 2.0], [300.0, 300.0]),
    ],
)
def test_traces_of_different_lengths_or_not_numbers_are_refused(call):
    with pytest.raises(ControlError, match="position"):
        call()


def test_a_position_that_is_nan_has_no_segment():
    """segment_index put NaN in the last segment; callers that did not mask it charged it
    there. gd_errors leaves such estimates out (above); the index refuses them."""
    from control.metrics import segment_index

    assert segment_index(TRACK, [-5.0, 10.0, 60.0, 149.0, 1e9]).tolist() == [0, 0, 1, 2, 2]
    with pytest.raises(ControlError, match=r"position holds NaN .*no segment"):
        segment_index(TRACK, [10.0, np.nan])
    with pytest.raises(ControlError, match="position"):
        segment_index(TRACK, ["10"])


BAD_TRACKS = [
    (None, "NoneType"),
    ("track", "str"),
    (SimpleNamespace(segments=((50.0, 300.0),)), "boundaries_m"),
    (SimpleNamespace(segments=((50.0, 300.0),), boundaries_m=(0.0, 50.0)), "one start"),
    (SimpleNamespace(segments=(), boundaries_m=()), "no segment"),
    (SimpleNamespace(segments=(("a", "b"),), boundaries_m=(0.0,)), "segments"),
    (SimpleNamespace(segments=((50.0, 300.0), (50.0, 500.0)), boundaries_m=(50.0, 0.0)), "increas"),
]


@pytest.mark.parametrize("track, what", BAD_TRACKS)
def test_the_metrics_refuse_what_is_no_track_naming_it(track, what):
    """None gave an AttributeError; boundaries that do not match the segments were read as
    they came."""
    from control.metrics import segment_index

    for call in (
        lambda: segment_index(track, [1.0]),
        lambda: gd_errors(track, [1.0], [300.0]),
        lambda: detection_delays(track, [1.0], [300.0]),
        lambda: fast_on_rough_m(track, [1.0, 2.0], [1.0, 1.0], 350.0, 1.0),
    ):
        with pytest.raises(ControlError, match=rf"^track\b.*{what}"):
            call()


def test_fast_on_rough_refuses_positions_that_go_backwards():
    with pytest.raises(ControlError, match="non-decreasing"):
        fast_on_rough_m(TRACK, [69.0, 62.0], [2.0, 2.0], 350.0, 1.0)


def test_pooled_rmse_names_the_one_run_mistake():
    errs = gd_errors(TRACK, [10.0], [310.0])
    with pytest.raises(ControlError, match=r"\[metrics.gd_errors\]"):
        pooled_rmse(errs, 300.0)
    assert pooled_rmse([errs], 300.0) == pytest.approx(10.0)


def test_clustered_mean_treats_each_run_as_one_draw():
    rng = np.random.default_rng(5)
    runs = [rng.normal(loc, 1.0, size=20) for loc in rng.normal(0.0, 2.0, size=8)]
    mean, se = clustered_mean(runs)
    means = np.array([r.mean() for r in runs])
    assert mean == pytest.approx(means.mean())  # equal sizes: the mean of the run means
    assert se == pytest.approx(means.std(ddof=1) / np.sqrt(means.size))
    # a run's values are not independent draws: the naive se is far smaller here
    assert se > 2 * np.concatenate(runs).std(ddof=1) / np.sqrt(160)


def test_clustered_mean_weighs_runs_by_their_values_and_leaves_empty_runs_out():
    mean, se = clustered_mean([[1.0, 1.0, 1.0], [4.0], []])
    assert mean == pytest.approx(7.0 / 4)
    # runs' sums minus mean x size: -2.25 and +2.25; sqrt(2 x 2.25^2) / 4 x sqrt(2 / 1)
    assert se == pytest.approx(np.sqrt(2 * 2.25**2) / 4 * np.sqrt(2))
    assert clustered_mean([[2.0, 3.0]]) == (2.5, pytest.approx(np.nan, nan_ok=True))
    assert all(np.isnan(clustered_mean([[], []])))


@pytest.mark.parametrize("bad", [[[1.0, np.nan], [2.0]], [[[1.0]], [2.0]], [1.0, 2.0], [["a"]]])
def test_clustered_mean_refuses_what_is_not_runs_of_finite_values(bad):
    with pytest.raises(ControlError, match=r"per_run\[0\]"):
        clustered_mean(bad)


def test_a_run_timed_at_zero_wall_clock_has_no_real_time_factor_not_a_crash():
    """As `ReplayResult.real_time_factor`: NaN (null in the JSON) where no time was measured."""
    import json

    from control import LoopMetrics

    metrics = LoopMetrics((), (), 0.0, 12.0, 0.0, np.nan, np.nan, 0.0)
    assert np.isnan(metrics.real_time_factor)
    assert json.loads(json.dumps(metrics.as_dict(), allow_nan=False))["real_time_factor"] is None
    assert LoopMetrics((), (), 0.0, 12.0, 3.0, np.nan, np.nan, 0.0).real_time_factor == 4.0


@pytest.mark.parametrize("value", [None, 5, 2.5])
def test_clustered_mean_of_something_that_holds_no_runs_is_a_control_error(value):
    with pytest.raises(ControlError, match="per_run must hold one sequence of values per run"):
        clustered_mean(value)
