"""BCR with a test-double calibrator: buffering, guards, filtering of disjoint windows."""

import numpy as np
import pytest
from conftest import FakeCalibrator, log_f, stream

from control import BCR, ControlError


def feed(bcr, t, p, a, v, chunk=125):
    out = []
    for k in range(0, t.size, chunk):
        out.append(
            bcr.update(t[k : k + chunk], p[k : k + chunk], a[k : k + chunk], v[k : k + chunk])
        )
    return out


def const(gd):
    return lambda s: np.full_like(s, gd)


def test_no_number_until_the_buffer_is_full(fake_calibrator):
    bcr = BCR(fake_calibrator, feature="log_var")
    ests = feed(bcr, *stream(const(400), 1.5, 12.5, seed=1))  # 12 updates
    # Windows of 1,000 samples: the first 7 updates (875 samples) have no estimate.
    assert [e.status for e in ests[:7]] == ["filling"] * 7
    assert all(np.isnan(e.gd_mean) and "buffer holds" in e.reason for e in ests[:7])
    assert ests[7].ok and np.isfinite(ests[7].gd_mean) and ests[7].latency_s > 0
    assert fake_calibrator.calls == len(ests) - 7


def test_estimates_cover_the_truth_and_filtering_beats_one_window():
    errors = {"filter": [], "tempered": [], "window": []}
    inside = 0
    for seed in range(4):
        t, p, a, v = stream(const(420), 1.2, 120, seed=seed)
        for method in errors:
            ests = [
                e
                for e in feed(BCR(FakeCalibrator(), feature="log_var", method=method), t, p, a, v)
                if e.ok
            ]
            errors[method] += [e.gd_mean - 420 for e in ests]
            if method == "filter":
                inside += sum(e.interval[0] <= 420 <= e.interval[1] for e in ests[::8])
    rmse = {k: np.sqrt(np.mean(np.square(e))) for k, e in errors.items()}
    assert rmse["filter"] < 0.7 * rmse["window"]
    assert rmse["tempered"] < 0.7 * rmse["window"]
    n_checked = 4 * len(range(0, 105, 8))
    assert inside >= 0.75 * n_checked  # a 90% interval: allow for the few windows checked


def test_filter_follows_a_step_as_fast_as_one_window():
    gd = lambda s: np.where(s < 60, 300.0, 500.0)  # noqa: E731
    t, p, a, v = stream(gd, 1.5, 100, seed=3)
    res = {}
    for method in ("filter", "tempered", "window"):
        ests = [
            e
            for e in feed(BCR(FakeCalibrator(), feature="log_var", method=method), t, p, a, v)
            if e.ok
        ]
        pos = np.array([e.position for e in ests])
        mean = np.array([e.gd_mean for e in ests])
        res[method] = pos[np.argmax((pos > 60) & (mean > 400))] - 60
    assert res["filter"] <= res["window"] + 2.0  # within about one update (1.6 m)
    # the tempered filter weighs the windows straddling the step: later, but within a window
    assert res["window"] < res["tempered"] < res["window"] + 12.5
    assert res["window"] < 12.5  # less than one window length at 1.5 m/s


def test_nan_samples_give_a_fault_then_recovery(fake_calibrator):
    t, p, a, v = stream(const(400), 1.5, 40, seed=2)
    a = a.copy()
    a[2000:2010] = np.nan
    ests = feed(BCR(fake_calibrator, feature="log_var"), t, p, a, v)
    status = [e.status for e in ests]
    k = 2000 // 125
    assert status[k - 1] == "ok"
    assert status[k] == "sensor_fault" and "10 non-finite" in ests[k].reason
    assert set(status[k + 1 : k + 8]) == {"filling"}  # the window restarts after the fault
    assert status[k + 9 :] and set(status[k + 9 :]) == {"ok"}


def test_dropped_samples_are_detected(fake_calibrator):
    t, p, a, v = stream(const(400), 1.5, 20, seed=2)
    keep = np.ones(t.size, bool)
    keep[1500:1530] = False
    ests = feed(BCR(fake_calibrator, feature="log_var"), t[keep], p[keep], a[keep], v[keep])
    faults = [e for e in ests if e.status == "sensor_fault"]
    assert len(faults) == 1 and "30 dropped" in faults[0].reason


def test_speed_outside_the_emulator_domain(fake_calibrator):
    ests = feed(BCR(fake_calibrator, feature="log_var"), *stream(const(400), 0.3, 12, seed=1))
    assert ests[-1].status == "out_of_domain" and "0.3 m/s" in ests[-1].reason
    assert np.isnan(ests[-1].gd_mean)


def test_an_old_estimate_turns_stale(fake_calibrator):
    bcr = BCR(fake_calibrator, feature="log_var", update_every=1000, max_age_s=1.0)
    t, p, a, v = stream(const(400), 1.5, 13, seed=1)
    assert bcr.update(t[:1000], p[:1000], a[:1000], v[:1000]).ok
    late = bcr.update(t[1000:1500], p[1000:1500], a[1000:1500], v[1000:1500])
    assert late.status == "stale" and "s old" in late.reason and np.isnan(late.gd_mean)


def test_calibrator_errors_become_a_status():
    class Refusing(FakeCalibrator):
        def log_likelihood_grid(self, x_obs, y_obs):
            raise ValueError("x_obs outside the domain")

    ests = feed(BCR(Refusing(), feature="log_var"), *stream(const(400), 1.5, 10, seed=1))
    assert ests[-1].status == "calibration_failed" and "outside" in ests[-1].reason


def test_windows_in_one_interleaved_filter_do_not_overlap(fake_calibrator):
    kw = {"feature": "log_var", "method": "filter"}
    bcr = BCR(fake_calibrator, buffer=1000, update_every=125, **kw)
    assert len(bcr.trackers) == 8
    bcr3 = BCR(FakeCalibrator(), buffer=1000, update_every=300, **kw)
    assert len(bcr3.trackers) == 4  # windows 1,200 samples apart
    assert len(BCR(FakeCalibrator(), feature="log_var", method="tempered").trackers) == 1
    assert len(BCR(FakeCalibrator(), feature="log_var", method="window").trackers) == 1


def test_bad_input_raises(fake_calibrator):
    with pytest.raises(ControlError, match="buffer must be an integer >= 10"):
        BCR(fake_calibrator, feature="log_var", buffer=5)
    with pytest.raises(ControlError, match="method must be one of"):
        BCR(fake_calibrator, feature="log_var", method="kalman")
    with pytest.raises(ControlError, match="rate_hz must be > 0"):
        BCR(fake_calibrator, feature="log_var", rate_hz=0)
    bcr = BCR(fake_calibrator, feature="log_var")
    with pytest.raises(ControlError, match="accel must be 1-D of length 3"):
        bcr.update(np.arange(3.0), np.arange(3.0), np.arange(2.0), np.ones(3))
    with pytest.raises(ControlError, match="t and position must be finite"):
        bcr.update(np.array([0.0, np.nan]), np.zeros(2), np.zeros(2), np.ones(2))


def square_wave(duration_s, speed=1.5, gd=400.0, rate_hz=120.0):
    """Accelerations +-a (f = a^2 as for GD `gd`): every window has the same f and likelihood."""
    amp = np.exp(0.5 * log_f(speed, gd))
    n = int(round(duration_s * rate_hz))
    t = np.arange(1, n + 1) / rate_hz
    return t, speed * t, amp * np.where(np.arange(n) % 2, 1.0, -1.0), np.full(n, speed)


def rigid_tracker():
    from control import TrackerSettings

    return TrackerSettings(mean_segment_m=1e9, drift_per_sqrt_m=0.0)


def test_tempered_updates_count_each_sample_once(fake_calibrator):
    """With nothing changing, 1,000 new samples in 8 tempered updates weigh one full window."""
    from control import GDTracker

    t, p, a, v = square_wave(8000 / 120)  # 8 windows' worth: 57 updates with an estimate
    ests = [
        e
        for e in feed(
            BCR(FakeCalibrator(), feature="log_var", method="tempered", tracker=rigid_tracker()),
            t,
            p,
            a,
            v,
        )
        if e.ok
    ]
    one = [
        e
        for e in feed(BCR(FakeCalibrator(), feature="log_var", method="window"), t, p, a, v)
        if e.ok
    ]
    assert ests[0].gd_sd == pytest.approx(one[0].gd_sd, rel=1e-9)  # the first window: power 1
    grid, loglik = fake_calibrator.log_likelihood_grid([[1.5]], [[ests[0].feature]])
    for k_windows in (2, 4, 8):
        ref = GDTracker((200.0, 600.0), rigid_tracker())
        for _ in range(k_windows):
            ref.update(grid, loglik)
        est = ests[8 * (k_windows - 1)]  # 1,000 (k - 1) samples after the first window
        assert est.gd_sd == pytest.approx(ref.posterior().sd("GD"), rel=1e-6)
        assert est.gd_mean == pytest.approx(ref.posterior().mean("GD"), rel=1e-9)
    # Double counting (power 1 for every overlapping window) would shrink the sd by sqrt(8).
    assert ests[8].gd_sd > 0.9 * one[0].gd_sd / np.sqrt(2)


def test_a_restarted_buffer_enters_at_full_power(fake_calibrator, monkeypatch):
    bcr = BCR(fake_calibrator, feature="log_var", method="tempered")
    powers = []
    update = bcr.trackers[0].update
    monkeypatch.setattr(
        bcr.trackers[0],
        "update",
        lambda g, ll, power=1.0: (powers.append(power), update(g, ll, power)),
    )
    t, p, a, v = stream(const(400), 1.5, 30, seed=4)
    a = a.copy()
    a[2000:2005] = np.nan
    feed(bcr, t, p, a, v)
    # first window, 7 tempered updates, (fault), refilled window, tempered updates
    n_before = 2000 // 125 - 7
    assert powers[0] == 1.0 and set(powers[1:n_before]) == {0.125}
    assert powers[n_before] == pytest.approx(1.0, abs=0.01)
    assert set(powers[n_before + 1 :]) == {0.125}


def test_the_speed_domain_edge_is_inside():
    cal = FakeCalibrator(v_range=(0.5, float(np.nextafter(2.0, 0.0))))  # 1.9999999999999998
    ests = feed(BCR(cal, feature="log_var"), *stream(const(400), 2.0, 10, seed=1))
    assert ests[-1].ok and ests[-1].speed == 2.0
    ests = feed(BCR(cal, feature="log_var"), *stream(const(400), 2.001, 10, seed=1))
    assert ests[-1].status == "out_of_domain"


def test_the_window_method_keeps_the_prior_setting(fake_calibrator):
    from control import TrackerSettings

    bcr = BCR(
        fake_calibrator,
        feature="log_var",
        method="window",
        tracker=TrackerSettings(prior="log_uniform", n_grid=200),
    )
    (tracker,) = bcr.trackers
    assert tracker.settings.mean_segment_m == 0.0
    assert (tracker.settings.prior, tracker.settings.n_grid) == ("log_uniform", 200)
