"""The BCR at the edges: checked window samples, data time, standstill, wild speeds, per-part fault
reasons, ignored feature and tracker settings."""

import numpy as np
import pytest
from control_doubles import FakeBlockModel, FakeCalibrator, stream

from control import (
    BCR,
    PAPER_WINDOW,
    ChangePointFilter,
    ControlError,
    FeatureSpec,
    TrackerSettings,
)
from control.sensor_checks import MAX_SPEED_MPS, stream_breaks, timing_fault

WINDOW_METHODS = ("window", "filter", "tempered")
CHUNK = 125  # the window methods' default update_every, and one change-point block


def const(gd):
    return lambda s: np.full_like(s, gd)


def feed(bcr, t, p, a, v, chunk=CHUNK, **kw):
    return [
        bcr.update(t[k : k + chunk], p[k : k + chunk], a[k : k + chunk], v[k : k + chunk], **kw)
        for k in range(0, t.size, chunk)
    ]


# --- 1: every sample of a window is checked, also while the window fills -----------------------


@pytest.mark.parametrize("method", WINDOW_METHODS)
def test_a_stuck_sensor_while_the_window_fills_never_enters_an_estimate(method):
    t, p, a, v = stream(const(400), 1.5, 14, seed=1)
    a = a.copy()
    a[:500] = 0.37  # stuck for the first four updates, then fine
    ests = feed(BCR(FakeCalibrator(), feature=PAPER_WINDOW, method=method), t, p, a, v)
    assert [e.status for e in ests[:4]] == ["sensor_fault"] * 4
    assert all("stuck sensor" in e.reason for e in ests[:4])
    # the first estimate waits for a window of 1,000 clean samples (500-1499: update 11)
    first_ok = next(i for i, e in enumerate(ests) if e.ok)
    assert first_ok == 11, [e.status for e in ests]


def test_samples_kept_after_a_break_are_checked_in_the_update_that_reports_it():
    t, p, a, v = stream(const(400), 1.5, 12, seed=1)
    t, a = t.copy(), a.copy()
    t[CHUNK:] += 0.5  # a gap just before update 1's samples, which are then kept...
    a[CHUNK : 2 * CHUNK] = 0.37  # ...but stuck
    ests = feed(BCR(FakeCalibrator(), feature=PAPER_WINDOW, method="window"), t, p, a, v)
    assert ests[1].status == "sensor_fault"
    assert "gap" in ests[1].reason and "stuck sensor" in ests[1].reason
    # without the stuck samples the window starts at sample 250: full at update 9
    assert not ests[8].ok and ests[9].ok, [e.status for e in ests]


def test_a_window_that_starts_moving_is_not_a_level_jump():
    """A vehicle that starts within the first update reads a quiet start: a change of level
    with the speed, not a sensor fault (the shipped examples' drives start so)."""
    t, _, a, v = stream(const(400), 1.5, 10, seed=1)
    a, v = a.copy(), v.copy()
    v[:10] = np.linspace(0.15, 1.5, 10)
    a[:40] *= 0.01
    p = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    ests = feed(BCR(FakeCalibrator(), feature=PAPER_WINDOW, method="window"), t, p, a, v)
    assert [e.status for e in ests[:7]] == ["filling"] * 7 and ests[7].ok


# --- 2: the data time is the newest sample's, not the caller's clock ---------------------------


@pytest.mark.parametrize("kind", ["changepoint", "window"])
def test_a_wild_clock_does_not_become_the_data_time(kind):
    if kind == "changepoint":
        bcr = BCR(FakeBlockModel(), update_every=CHUNK)
    else:
        bcr = BCR(FakeCalibrator(), feature=PAPER_WINDOW, method="window")
    t, p, a, v = stream(const(400), 1.5, 1000 / 120, seed=1)
    for k in range(0, 1000, CHUNK):
        now = 1e9 if k == 1000 - CHUNK else t[k + CHUNK - 1]
        bcr.update(t[k : k + CHUNK], p[k : k + CHUNK], a[k : k + CHUNK], v[k : k + CHUNK], now=now)
    assert bcr.last.ok and bcr.last.data_time == t[999]


def test_after_a_wild_clock_an_estimate_still_turns_stale():
    bcr = BCR(FakeBlockModel(), update_every=CHUNK)
    t, p, a, v = stream(const(400), 1.5, 1000 / 120, seed=1)
    for k in range(0, 1000, CHUNK):
        now = 1e9 if k == 1000 - CHUNK else t[k + CHUNK - 1]
        bcr.update(t[k : k + CHUNK], p[k : k + CHUNK], a[k : k + CHUNK], v[k : k + CHUNK], now=now)
    rest = np.random.default_rng(2).normal(0.0, 0.01, CHUNK)  # a sensor at rest: its noise
    for k in range(10):  # 10 s standing still, the caller's clock sane again
        standing = t[-1] + (k * CHUNK + np.arange(1, CHUNK + 1)) / 120
        est = bcr.update(standing, np.full(CHUNK, p[-1]), rest, np.zeros(CHUNK),
                         now=standing[-1])  # fmt: skip
    assert est.status == "stale" and "old (max_age_s = 5)" in est.reason


# --- 3: a standstill leaves the change-point state as it is ------------------------------------


def test_no_distance_leaves_the_run_length_posterior_unchanged():
    f = ChangePointFilter(np.geomspace(200.0, 600.0, 121))
    for _ in range(20):
        f.update(-0.5 * ((np.log(f.gd) - np.log(400.0)) / 0.3) ** 2, 1.5)
    mass, dist, _ = f.state()
    for _ in range(2 * f.settings.max_runs):  # far beyond max_runs: would merge real runs
        f.predict(0.0)
    after_mass, after_dist, _ = f.state()
    np.testing.assert_array_equal(after_mass, mass)
    np.testing.assert_array_equal(after_dist, dist)


def test_five_minutes_standing_still_leave_the_bcrs_runs_as_they_were():
    bcr = BCR(FakeBlockModel(), update_every=CHUNK)
    t, p, a, v = stream(const(400), 1.5, 30, seed=1)
    assert feed(bcr, t, p, a, v)[-1].ok
    n = CHUNK + 300 * 120  # the block that stops, then five minutes at 120 Hz
    standing = t[-1] + np.arange(1, n + 1) / 120
    noise = np.random.default_rng(2).standard_normal(n) * 0.01
    stopped = (standing, np.full(n, p[-1]), noise, np.zeros(n))
    feed(bcr, *(x[:CHUNK] for x in stopped))  # ends the block the vehicle stopped in
    mass, dist, _ = bcr.filter.state()
    assert dist.size > 20  # the runs of the drive
    out = feed(bcr, *(x[CHUNK:] for x in stopped), chunk=12 * CHUNK)
    assert out[-1].status == "stale"
    after_mass, after_dist, _ = bcr.filter.state()
    np.testing.assert_array_equal(after_dist, dist)
    np.testing.assert_array_equal(after_mass, mass)


# --- 4: a speed beyond any ground robot's is a fault, without overflow ------------------------


@pytest.mark.parametrize("kind", ["changepoint", "window"])
@pytest.mark.parametrize("where", [slice(875, 1000), slice(950, 951)])
def test_an_absurd_speed_is_a_sensor_fault(kind, where):
    if kind == "changepoint":
        bcr = BCR(FakeBlockModel(), update_every=CHUNK)
    else:
        bcr = BCR(FakeCalibrator(), feature=PAPER_WINDOW, method="window")
    t, p, a, v = stream(const(400), 1.5, 1000 / 120, seed=1)
    v = v.copy()
    v[where] = 1.7e308
    with np.errstate(all="raise"):  # no overflow on the way: the range check comes first
        ests = feed(bcr, t, p, a, v)
    assert ests[-1].status == "sensor_fault"
    assert f"beyond any ground robot's (MAX_SPEED_MPS = {MAX_SPEED_MPS:g} m/s)" in ests[-1].reason


def test_the_stream_and_timing_checks_name_an_absurd_speed():
    t = np.arange(1, 11) / 120.0
    speed = np.full(10, 1.0)
    speed[3] = -1e300
    drop, _, breaks = stream_breaks(t, t.copy(), np.zeros(10), speed, np.nan, 120.0)
    reason = breaks.reason(120.0)
    assert drop.tolist() == [i == 3 for i in range(10)]
    assert reason.startswith("1 sample(s) with |speed| up to 1e+300 m/s")
    from control.sensor_checks import SensorLimits

    with np.errstate(all="raise"):
        why = timing_fault(t, t.copy(), speed, 120.0, SensorLimits())
    assert why.startswith("out of range: |speed| reaches 1e+300 m/s")
    calm = stream_breaks(t, t.copy(), np.zeros(10), np.full(10, -2.0), np.nan, 120.0)[2]
    assert calm.reason(120.0) == ""


# --- 5: each update's fault reason names its own fault -----------------------------------------


def _faulty_call(first_fault: str):
    t, p, a, v = stream(const(400), 1.5, 6, seed=1)
    t, a = t.copy(), a.copy()
    nan_at, gap_at = (10, 400) if first_fault == "nan" else (400, 10)
    a[nan_at] = np.nan
    t[gap_at:] += 0.5
    return t, p, a, v


@pytest.mark.parametrize("first_fault", ["nan", "gap"])
def test_each_fault_of_one_call_is_named_where_it_happened(first_fault, monkeypatch):
    bcr = BCR(FakeBlockModel(), update_every=CHUNK)
    made = []
    estimate = bcr._estimate
    monkeypatch.setattr(bcr, "_estimate", lambda: made.append(estimate()) or made[-1])
    est = bcr.update(*_faulty_call(first_fault))
    nan_part, gap_part = (made[0], made[3]) if first_fault == "nan" else (made[3], made[0])
    assert nan_part.status == gap_part.status == "sensor_fault"
    assert "non-finite accel" in nan_part.reason and "gap" not in nan_part.reason
    assert "gap" in gap_part.reason and "non-finite" not in gap_part.reason
    assert est.reason == made[0].reason  # the call reports its first (gravest) fault


# --- 6 and 7: settings that the chosen feature or method would ignore are refused ---------------


@pytest.mark.parametrize("name", ["log_var", "var"])
@pytest.mark.parametrize(
    "field, value",
    [("bands_hz", (5.0, 1.0)), ("bands_hz", (1.0, 5.0)), ("taper_nw", -3.0), ("n_tapers", 99)],
)
def test_band_settings_are_refused_by_the_window_features(name, field, value):
    with pytest.raises(ControlError, match=rf"^{field} = .* is ignored by the '{name}' feature"):
        FeatureSpec(name=name, block_samples=1000, **{field: value})


def test_the_window_features_still_check_their_types_and_take_the_defaults():
    with pytest.raises(ControlError, match="n_tapers must be an integer"):
        FeatureSpec(name="log_var", block_samples=1000, n_tapers=3.5)
    spec = FeatureSpec(name="log_var", block_samples=1000, rate_hz=50.0)  # default bands > Nyquist
    assert FeatureSpec.from_dict(spec.to_dict()) == spec
    assert FeatureSpec(name="var", block_samples=1000, n_tapers=np.int64(3)).n_tapers == 3


@pytest.mark.parametrize(
    "tracker, message",
    [
        (TrackerSettings(mean_segment_m=100.0), "tracker.mean_segment_m = 100 is ignored"),
        (TrackerSettings(drift_per_sqrt_m=0.2), "tracker.drift_per_sqrt_m = 0.2 is ignored"),
    ],
)
def test_the_window_method_refuses_a_tracker_memory_it_would_ignore(tracker, message):
    with pytest.raises(ControlError, match=rf"{message} by method 'window'"):
        BCR(FakeCalibrator(), feature=PAPER_WINDOW, method="window", tracker=tracker)
    for method in ("filter", "tempered"):  # these use it
        assert BCR(FakeCalibrator(), feature=PAPER_WINDOW, method=method, tracker=tracker)
    for ok in (TrackerSettings(), TrackerSettings(mean_segment_m=0.0)):
        assert BCR(FakeCalibrator(), feature=PAPER_WINDOW, method="window", tracker=ok)


@pytest.mark.parametrize("method", WINDOW_METHODS)
def test_the_change_point_filter_of_a_window_method_is_a_control_error(method):
    bcr = BCR(FakeCalibrator(), feature=PAPER_WINDOW, method=method)
    with pytest.raises(ControlError, match=rf"filter needs method 'changepoint', not '{method}'"):
        bcr.filter  # noqa: B018 (a property)
    assert BCR(FakeBlockModel()).filter.gd.size  # the change-point method has one
