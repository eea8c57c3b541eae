"""Paths of control that no test reached before session 84's coverage review: each settings
check's message (an infinite value was told a rule it meets: "must be >= 0, got inf"), the
window BCR's hold of its last estimate past the speed domain, and the odd inputs of the
metrics, plots and checks that their own guards refuse."""

import math

import matplotlib
import numpy as np
import pytest
from control_doubles import FakeCalibrator, stream

matplotlib.use("Agg")

import roadgen  # noqa: E402
from control import (  # noqa: E402
    BCR,
    PAPER_WINDOW,
    BCRSettings,
    BlockScatter,
    ChangePointSettings,
    ControlError,
    FeatureSpec,
    GDTracker,
    SensorFault,
    SensorLimits,
    TrackerSettings,
    fast_on_rough_m,
    pooled_rmse,
    run_closed_loop,
)
from control.compat import one_observation_posteriors  # noqa: E402
from control.plotting import plot_gd_trace, plot_posterior_grid, plot_speed  # noqa: E402

INF = math.inf


@pytest.mark.parametrize(
    ("make", "match"),
    [  # an infinite value: the message says finite (it said "must be >= 0, got inf")
        (lambda: BCRSettings(recent_change_m=INF), r"recent_change_m must be >= 0 and finite"),
        (lambda: SensorFault(start_s=INF, duration_s=1.0), r"start_s must be >= 0 and finite"),
        (lambda: SensorFault(start_s=0.0, duration_s=INF), r"duration_s must be > 0 and finite"),
        (lambda: FeatureSpec(rate_hz=INF), r"rate_hz must be > 0 and finite"),
        (lambda: GDTracker((1.0, INF)), r"0 < lo < hi, both finite"),
    ],
)
def test_an_infinite_setting_is_told_that_it_must_be_finite(make, match):
    with pytest.raises(ControlError, match=match):
        make()


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: BCRSettings(max_age_s=0.0), r"max_age_s must be finite and > 0, got 0"),
        (lambda: BCRSettings(max_silence_s=INF), r"max_silence_s must be finite and > 0"),
        (lambda: BCRSettings(interval_level=1.0), r"interval_level must lie in \(0, 1\)"),
        (lambda: BCRSettings(plausibility_p=1.0), r"plausibility_p must lie in \[0, 1\)"),
        (lambda: BCRSettings(recent_change_m=-1.0), r"recent_change_m must be >= 0"),
        (lambda: ChangePointSettings(segment_shape=0.0), r"segment_shape must be finite and > 0"),
        (lambda: ChangePointSettings(min_jump=INF), r"min_jump must be finite and >= 0"),
        (lambda: ChangePointSettings(jump_sd=0.0), r"jump_sd must be None or finite and > 0"),
        (lambda: ChangePointSettings(max_runs=1), r"max_runs must be an integer >= 2, got 1"),
        (lambda: SensorFault(0.0, 1.0, magnitude=INF), r"magnitude must be finite and > 0"),
        (lambda: SensorFault(-1.0, 1.0), r"start_s must be >= 0"),
        (lambda: FeatureSpec(rate_hz=0.0), r"rate_hz must be > 0"),
        (lambda: FeatureSpec(bands_hz=(5.0, 3.0)), r"bands_hz must be >= 2 increasing edges"),
        (lambda: FeatureSpec(bands_hz=(5.0,)), r"bands_hz must be >= 2 increasing edges"),
        (lambda: FeatureSpec(taper_nw=0.0), r"taper_nw must lie in \(0, block_samples / 2\)"),
        (lambda: TrackerSettings(drift_per_sqrt_m=-1.0), r"drift_per_sqrt_m must be finite"),
        (lambda: SensorLimits(max_level_jump=1.0), r"max_level_jump must be finite and > 1"),
        (lambda: SensorLimits(dead_fraction=1.0), r"dead_fraction must lie in \[0, 1\)"),
        (lambda: SensorLimits(free_fall_mps2=INF), r"free_fall_mps2 must be None or finite"),
        (lambda: SensorLimits(range_mps2=0.0), r"range_mps2 must be None or finite and > 0"),
    ],
)
def test_each_settings_check_names_the_field_and_its_rule(make, match):
    with pytest.raises(ControlError, match=match):
        make()


def test_the_window_features_variance_units_and_the_window_method_runs_one_phase():
    assert FeatureSpec(name="var").units() == ["(m/s^2)^2"]
    assert BCRSettings(method="window", feature=PAPER_WINDOW).phases == 1


@pytest.mark.parametrize(
    ("speed", "cov", "dof", "match"),
    [
        ([1.0], np.eye(2)[None], INF, r"speed must be >= 2 increasing finite nodes"),
        ([2.0, 1.0], np.stack([np.eye(2)] * 2), INF, r"speed must be >= 2 increasing"),
        ([1.0, 2.0], np.eye(2), INF, r"cov must have shape \(2, K, K\), got \(2, 2\)"),
        ([1.0, 2.0], np.full((2, 2, 2), np.nan), INF, r"cov must hold finite"),
        ([1.0, 2.0], np.stack([np.eye(2)] * 2), 2.0, r"dof must be > 2 \(or inf\), got 2"),
    ],
)
def test_a_block_scatter_that_is_no_covariance_law_is_refused(speed, cov, dof, match):
    with pytest.raises(ControlError, match=match):
        BlockScatter(speed=speed, cov=cov, dof=dof)


def test_a_tracker_update_with_grids_of_other_shapes_is_refused():
    tracker = GDTracker((200.0, 600.0))
    with pytest.raises(ControlError, match=r"grid/loglik must be 1-D of equal length"):
        tracker.update(np.array([200.0, 300.0, 400.0]), np.zeros(2), 1.0)


def _feed(bcr, t, p, a, v, chunk=125):
    return [
        bcr.update(t[k : k + chunk], p[k : k + chunk], a[k : k + chunk], v[k : k + chunk])
        for k in range(0, t.size, chunk)
    ]


def test_the_window_bcr_holds_its_last_estimate_past_the_speed_domain_then_it_turns_stale():
    bcr = BCR(FakeCalibrator(), method="window", feature=PAPER_WINDOW)  # speeds [0.5, 2] m/s
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 10, seed=1)
    last = _feed(bcr, t, p, a, v)[-1]
    assert last.ok
    t2, p2, a2, v2 = stream(lambda s: np.full_like(s, 400.0), 2.1, 16, seed=2, t0=t[-1], s0=p[-1])
    ests = _feed(bcr, t2, p2, a2, v2)
    held = [e for e in ests if "outside the emulator's range" in e.reason]
    assert held and held[0].ok and held[0].reason.startswith("no new information: window speed")
    assert "[0.5, 2] m/s" in held[0].reason
    ok_held = [e for e in held if e.ok]
    assert len({e.gd_mean for e in ok_held}) == 1  # the last estimate, unchanged
    assert all(e.time - e.data_time <= bcr.settings.max_age_s + 1e-9 for e in ok_held)
    assert ests[-1].status in ("stale", "out_of_domain") and np.isnan(ests[-1].gd_mean)


def test_an_estimate_without_a_posterior_has_nan_quantiles():
    bcr = BCR(FakeCalibrator(), method="window", feature=PAPER_WINDOW)
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 1, seed=1)
    first = bcr.update(t, p, a, v)
    assert first.status == "filling" and np.isnan(first.quantile(0.5))
    with pytest.raises(ControlError, match=r"q must be a probability in \[0, 1\]"):
        first.quantile(1.5)


def test_odd_inputs_of_the_metrics_and_the_closed_loop_are_named():
    track = roadgen.track([(25, 300), (25, 500)], seed=3)
    assert fast_on_rough_m(track, [1.0], [1.0], 350.0, 1.0) == 0.0  # one sample: no distance
    assert fast_on_rough_m(track, [], [], 350.0, 1.0) == 0.0
    with pytest.raises(ControlError, match=r"one sequence of GDError per run: 'int' object"):
        pooled_rmse([5], 300.0)
    for faults in (5, object()):  # refused before the drive
        with pytest.raises(ControlError, match=r"faults must be a sequence of SensorFault, got"):
            run_closed_loop(track, None, faults=faults)


def test_one_observation_posteriors_names_the_ends_it_reads(emulator_a):
    for ends in ((), ("middle",), "top"):
        with pytest.raises(ControlError, match=r"ends must be some of \('bottom', 'top'\)"):
            one_observation_posteriors(emulator_a, [1.0], ends=ends)


def test_plots_refuse_what_is_no_sequence_and_take_none_for_the_optional_lines():
    with pytest.raises(
        ControlError, match=r"results must be a sequence of ClosedLoopResults, got 5"
    ):
        plot_gd_trace(5, None)
    with pytest.raises(ControlError, match=r"cells must be a sequence of \(v, true GD, draws\)"):
        plot_posterior_grid(5)
    with pytest.raises(ControlError, match=r"gd_range=\('a', 'b'\) must be two finite GD"):
        plot_posterior_grid([(1.0, 300.0, [290.0, 310.0])], gd_range=("a", "b"))
    from _robot_cases import small_result

    track = roadgen.track([(25, 300), (25, 500)], seed=3)
    fig = plot_gd_trace([small_result()], track, gd_max=None)  # no rough parts shaded
    assert not any(type(p).__name__ == "Rectangle" and p.get_alpha() for p in fig.axes[0].patches)
    fig = plot_speed([small_result()], track, v_safe=None)
    assert not any("safe speed" in line.get_label() for line in fig.axes[0].lines)


@pytest.mark.parametrize("draws", [["a", "b"], [[1.0, 2.0], [3.0]]])
def test_draws_that_are_not_numbers_are_named_so_not_counted_as_one_non_finite_draw(draws):
    # before: "got 1 draws (1 not finite)" for two draws that were not numbers
    with pytest.raises(ControlError, match=r"cells\[0\]: the draws must be an array of GD values "
                                           r"\(numbers\), got \["):  # fmt: skip
        plot_posterior_grid([(1.0, 300.0, draws)])
