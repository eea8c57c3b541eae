"""What the BCR and the loop do with a stream at another rate, broken odometry and arguments of
the wrong kind: a sensor fault for what a robot can send, a ControlError for what a caller can
pass, never a silent estimate or a numpy traceback."""

import shutil
import types
from fractions import Fraction

import numpy as np
import pytest
from control_doubles import FakeBlockModel, stream

import control
import roadgen
from control import (
    BCR,
    BCRSettings,
    ChangePointFilter,
    ChangePointSettings,
    ControlError,
    EmulatorMismatchError,
    Estimate,
    SensorLimits,
    Simplex,
)


def const(gd):
    return lambda s: np.full_like(s, gd)


def statuses(bcr, t, p, a, v, chunk=42):
    run = Simplex().start()
    out = []
    for k in range(0, t.size, chunk):
        part = slice(k, k + chunk)
        est = bcr.update(t[part], p[part], a[part], v[part], now=float(t[part][-1]))
        run.command(est)
        out.append(est)
    return out, run


@pytest.mark.parametrize("rate_hz", [100.0, 130.0, 150.0])
def test_a_stream_at_another_rate_is_a_sensor_fault_that_latches(rate_hz):
    """Steps of 1/100-1/150 s pass the per-step check (within half a period of 1/120 s); the
    block's span gives the rate away, and the Simplex stays safe."""
    ests, run = statuses(BCR(FakeBlockModel()), *stream(const(300), 1.5, 20, rate_hz=rate_hz))
    assert not any(e.ok for e in ests)
    faults = [e for e in ests if e.status == "sensor_fault"]
    assert faults and "samples at another rate" in faults[0].reason
    assert f"({rate_hz:.4g} Hz)" in faults[0].reason
    assert run.latched


def test_jitter_within_the_tolerance_is_no_fault():
    t, p, a, v = stream(const(300), 1.5, 20)
    t = t + np.random.default_rng(1).uniform(-1e-3, 1e-3, t.size)  # +-1 ms on 8.3 ms steps
    ests, run = statuses(BCR(FakeBlockModel()), t, p, a, v)
    assert sum(e.ok for e in ests) > 0.9 * len(ests)
    assert not run.latched


@pytest.mark.parametrize(
    "break_odometry",
    [
        lambda p, k: np.where(np.arange(p.size) >= k, p[k], p),  # frozen
        lambda p, k: np.where(np.arange(p.size) >= k, 2 * p[k] - p, p),  # backwards
    ],
    ids=["frozen", "backwards"],
)
def test_broken_odometry_is_a_sensor_fault(break_odometry):
    t, p, a, v = stream(const(300), 1.5, 30)
    k = np.searchsorted(t, 15.0)
    ests, run = statuses(BCR(FakeBlockModel()), t, break_odometry(p, k), a, v)
    assert any(e.ok for e in ests[:30])  # before the break
    after = [e for e in ests if e.time > 16.5]
    assert after and not any(e.ok for e in after)
    assert any("odometry disagrees with the speeds" in e.reason for e in after)
    assert run.latched


def test_a_position_jump_is_a_sensor_fault_for_the_blocks_that_hold_it():
    t, p, a, v = stream(const(300), 1.5, 30)
    jumped = p + 1e6 * (t >= 15.0)
    ests, run = statuses(BCR(FakeBlockModel()), t, jumped, a, v)
    holding = [e for e in ests if 15.0 <= e.time < 15.0 + 125 / 120]
    assert holding and all(e.status == "sensor_fault" for e in holding)
    assert "odometry disagrees with the speeds" in holding[0].reason
    assert run.latched


def test_odometry_within_the_tolerance_is_no_fault():
    t, p, a, v = stream(const(300), 1.5, 20)
    ests, _ = statuses(BCR(FakeBlockModel()), t, 1.1 * p, a, v)  # 10% scale error
    assert not any(e.status == "sensor_fault" for e in ests)


@pytest.mark.parametrize(
    ("values", "match"),
    [
        (np.ones(42, bool), "must hold real numbers, got dtype bool"),
        (np.array(["1.5"] * 42, dtype=object), "must hold real numbers .*'1.5' \\(str\\)"),
        ([True] * 42, "must hold real numbers, got dtype bool"),
        ([[1.0, 2.0], [1.0]], "must be a 1-D sequence of numbers"),
        (None, "must be a 1-D sequence of numbers, got None"),
    ],
)
@pytest.mark.parametrize("name", ["position", "accel", "speed"])
def test_samples_of_the_wrong_kind_are_refused(name, values, match):
    t, p, a, v = stream(const(300), 1.5, 0.35)
    args = {"t": t, "position": p, "accel": a, "speed": v, name: values}
    with pytest.raises(ControlError, match=f"{name} {match}"):
        BCR(FakeBlockModel()).update(**args)


def test_none_inside_a_sequence_is_a_missing_sample():
    t, p, a, v = stream(const(300), 1.5, 0.35)
    accel = [None, *a[1:].tolist()]
    assert BCR(FakeBlockModel()).update(t, p, accel, v).status == "sensor_fault"


@pytest.mark.parametrize("value", [None, "350", [300, 400], True, np.nan])
def test_estimate_prob_above_takes_one_finite_gd(value):
    est = Estimate(time=0.0, position=0.0, status="filling")
    with pytest.raises(ControlError, match="value must be a finite GD"):
        est.prob_above(value)


@pytest.mark.parametrize("q", [None, "0.5", [0.1, 0.9], True, -0.1, 1.5])
def test_estimate_quantile_takes_one_probability(q):
    est = Estimate(time=0.0, position=0.0, status="filling")
    with pytest.raises(ControlError, match="q must be a probability"):
        est.quantile(q)


def test_an_estimate_names_a_status_or_edge_it_does_not_know():
    with pytest.raises(ControlError, match=r"status must be one of \('ok', 'filling'.*got 'bogus'"):
        Estimate(time=0.0, position=0.0, status="bogus")
    with pytest.raises(ControlError, match="domain_edge must be '' or one of .*got 'top'"):
        Estimate(time=0.0, position=0.0, status="ok", domain_edge="top")
    for pair in ((300.0,), (300.0, "400"), 300.0, (300.0, 200.0), (np.nan, 300.0)):
        with pytest.raises(ControlError, match=r"interval must (be a pair|have lo <= hi)"):
            Estimate(time=0.0, position=0.0, status="ok", interval=pair)
    assert Estimate(time=0.0, position=0.0, status="ok", interval=(250.0, 350.0)).interval


@pytest.mark.parametrize(
    "field, value",
    [("gd_mean", 300.0), ("gd_sd", 10.0), ("interval", (250.0, 350.0)), ("domain_edge", "upper")],
)
def test_an_estimate_that_is_not_ok_carries_none_of_the_posteriors_numbers(field, value):
    # a "stale" estimate holding a GD was counted as an estimate by the loop's metrics (which
    # read a finite gd_mean as one) while the Simplex drove it as none
    with pytest.raises(ControlError, match=f"a 'stale' estimate has no {field}"):
        Estimate(time=0.0, position=0.0, status="stale", **{field: value})
    assert Estimate(time=0.0, position=0.0, status="ok", **{field: value}).ok


def test_only_an_ok_estimate_holds_a_posterior():
    post = control.GDTracker((200.0, 600.0)).posterior()
    with pytest.raises(ControlError, match="a 'filling' estimate has no posterior"):
        Estimate(time=0.0, position=0.0, status="filling", posterior=post)
    ok = Estimate(time=0.0, position=0.0, status="ok", posterior=post)
    assert ok.quantile(0.0) == pytest.approx(200.0) and ok.quantile(1.0) == pytest.approx(600.0)
    with pytest.raises(ControlError, match="posterior must be a gpmsa.Posterior or None"):
        Estimate(time=0.0, position=0.0, status="ok", posterior="GD ~ 300")


def test_edge_counts_name_what_is_not_a_sequence_of_edges():
    # a result, a single string or a misspelt edge was counted as no edge: {"upper": 0, ...}
    assert control.edge_counts(np.array(["", "upper", "upper"], dtype=object)) == {
        "upper": 2, "lower": 0}  # fmt: skip
    assert control.edge_counts([]) == {"upper": 0, "lower": 0}
    for bad in (None, "upper", [["upper"]], ["upper", "top"], [1.0]):
        with pytest.raises(ControlError, match="domain_edge must be a sequence of '', 'upper'"):
            control.edge_counts(bad)


def test_the_simplex_and_the_recorder_name_an_argument_of_the_wrong_kind(tmp_path):
    for simplex in (Simplex(), Simplex().start()):
        with pytest.raises(ControlError, match="estimate must be a control.Estimate, got None"):
            simplex.command(None)
    with pytest.raises(ControlError, match="result must be a control.ClosedLoopResult, got 'r'"):
        control.record_run("r", tmp_path / "run.mcap")
    assert not (tmp_path / "run.mcap").exists()


@pytest.mark.parametrize("emulator", ["B", None, control.shipped_emulator_path("B")])
def test_something_other_than_an_emulator_is_named_not_sent_to_retraining(emulator):
    track = roadgen.track([(30, 300)], seed=1)
    why = r"emulator must be a gpmsa.Emulator \(gpmsa.load\(path\), or control.shipped_emulator"
    for call in (
        lambda: control.run_closed_loop(track, emulator, seed=1),
        lambda: BCR.from_emulator(emulator),
        lambda: control.check_emulator(emulator),
        lambda: control.emulator_noise_std(emulator),
    ):
        with pytest.raises(ControlError, match=why):
            call()


def test_settings_of_the_wrong_kind_are_named(emulator_a):
    with pytest.raises(ControlError, match="settings must be a control.BCRSettings, got {}"):
        BCR.from_emulator(emulator_a, {})
    with pytest.raises(ControlError, match="settings must be a control.BCRSettings"):
        BCR(FakeBlockModel(), {})
    with pytest.raises(ControlError, match="sensor must be a control.SensorLimits"):
        control.bcr_settings_for(emulator_a, sensor={})
    with pytest.raises(ControlError, match="feature must be a control.FeatureSpec"):
        control.bcr_settings_for(emulator_a, feature=0)
    with pytest.raises(ControlError, match="settings must be a control.ChangePointSettings"):
        ChangePointFilter(np.geomspace(200, 600, 9), {})


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"track": "GD 300"}, "track must be a roadgen.Track, got 'GD 300'"),
        ({"track": [(50, 300)]}, "track must be a roadgen.Track"),
        ({"bcr": {}}, "bcr must be a control.BCRSettings"),
    ],
)
def test_run_closed_loop_names_arguments_of_the_wrong_kind(emulator_a, kwargs, match):
    args = {"track": roadgen.track([(10, 300)], seed=0), "emulator": emulator_a, **kwargs}
    with pytest.raises(ControlError, match=match):
        control.run_closed_loop(**args)


def test_sensor_noise_beyond_any_accelerometer_is_refused():
    with pytest.raises(ControlError, match="noise_sd_mps2 must be None or lie in"):
        SensorLimits(noise_sd_mps2=1e300)
    assert BCRSettings(sensor=SensorLimits(noise_sd_mps2=1e4)).sensor.noise_sd_mps2 == 1e4


@pytest.mark.parametrize(
    ("field", "value"),
    [("rate_tolerance", 0.0), ("rate_tolerance", 0.5), ("odometry_tolerance", 1.0),
     ("odometry_slack_m", -0.1), ("odometry_slack_m", np.inf), ("rate_tolerance", "0.02")],
)  # fmt: skip
def test_timing_tolerances_are_checked(field, value):
    with pytest.raises(ControlError, match=field):
        SensorLimits(**{field: value})


def test_change_point_settings_name_what_is_wrong():
    grid = np.geomspace(200, 600, 41)
    with pytest.raises(ControlError, match="prior\\(gd\\) must return real log densities"):
        ChangePointFilter(grid, ChangePointSettings(prior=lambda gd: "x"))
    with pytest.raises(ControlError, match="with jump_sd = 1e-300 leaves no GD to jump to"):
        ChangePointFilter(grid, ChangePointSettings(jump_sd=1e-300))


def test_shipped_emulator_checks_its_folder_and_the_file_kind(tmp_path):
    with pytest.raises(ControlError, match="folder must be None or a path, got 3"):
        control.shipped_emulator("A", folder=3)
    window = control.shipped.shipped_emulator_path("A", "window")
    shutil.copyfile(window, tmp_path / control.shipped.emulator_file_name("A", "band"))
    with pytest.raises(EmulatorMismatchError, match="feature 'log_var', not of kind 'band'"):
        control.shipped_emulator("A", "band", folder=tmp_path)


@pytest.mark.parametrize("value", [10**400, 2**64, Fraction(1, 2)], ids=["huge", "2**64", "frac"])
@pytest.mark.parametrize(
    ("make", "field"),
    [
        (lambda v: BCRSettings(max_age_s=v), "BCRSettings.max_age_s"),
        (lambda v: BCRSettings(recent_change_m=v), "BCRSettings.recent_change_m"),
        (lambda v: control.FeatureSpec(rate_hz=v), "FeatureSpec.rate_hz"),
        (lambda v: SensorLimits(noise_floor=v), "SensorLimits.noise_floor"),
        (lambda v: SensorLimits(range_mps2=v), "SensorLimits.range_mps2"),
        (lambda v: control.TrackerSettings(mean_segment_m=v), "TrackerSettings.mean_segment_m"),
        (lambda v: ChangePointSettings(mean_segment_m=v), "ChangePointSettings.mean_segment_m"),
    ],
)
def test_a_number_numpy_cannot_hold_is_named_in_the_settings(make, field, value):
    """An int beyond 64 bits or a Fraction passed the real-number check and failed in numpy
    ("ufunc 'isfinite' not supported", or OverflowError)."""
    with pytest.raises(ControlError, match=rf"{field} must be a real number .*numpy holds"):
        make(value)


def test_a_clock_or_samples_numpy_cannot_hold_are_control_errors():
    bcr = BCR(FakeBlockModel())
    for now in (10**400, Fraction(1, 2)):  # TypeError: ufunc 'isfinite' not supported
        with pytest.raises(ControlError, match="now must be a finite time"):
            bcr.update([], [], [], [], now=now)
    t = np.arange(1, 4) / 120
    with pytest.raises(ControlError, match=r"accel must hold real numbers .*, got 1000+ \(int\)"):
        bcr.update(t, t, [0.0, 10**400, 1.0], np.ones(3))  # OverflowError in float()
    assert bcr.update(t, t, [0.0, 2**63, 1.0], np.ones(3)).status == "filling"


@pytest.mark.parametrize(
    ("kept", "simplex", "lacks"),
    [
        (("metadata", "x_names", "domain"), None, "t_names"),
        (("metadata",), None, "t_names, domain"),
        (("metadata", "t_names", "domain"), Simplex(), "x_names"),
    ],
)
def test_check_emulator_names_the_records_a_stand_in_lacks(kept, simplex, lacks):
    # session 91: an object with metadata but no t_names raised a bare AttributeError (a
    # stand-in without x_names is checked where no Simplex asks for its speed domain)
    emulator = control.shipped_emulator("B")
    stand_in = types.SimpleNamespace(**{name: getattr(emulator, name) for name in kept})
    with pytest.raises(ControlError) as info:
        control.check_emulator(stand_in, simplex=simplex)
    assert str(info.value).endswith(f"(SimpleNamespace, without {lacks})")
    assert str(info.value).startswith("emulator must be a gpmsa.Emulator (gpmsa.load(path)")
