"""BCR with a test-double calibrator: buffering, guards, filtering of disjoint windows."""

import numpy as np
import pytest
from conftest import FakeCalibrator, stream

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
    errors = {"filter": [], "window": []}
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
    n_checked = 4 * len(range(0, 105, 8))
    assert inside >= 0.75 * n_checked  # a 90% interval: allow for the few windows checked


def test_filter_follows_a_step_as_fast_as_one_window():
    gd = lambda s: np.where(s < 60, 300.0, 500.0)  # noqa: E731
    t, p, a, v = stream(gd, 1.5, 100, seed=3)
    res = {}
    for method in ("filter", "window"):
        ests = [
            e
            for e in feed(BCR(FakeCalibrator(), feature="log_var", method=method), t, p, a, v)
            if e.ok
        ]
        pos = np.array([e.position for e in ests])
        mean = np.array([e.gd_mean for e in ests])
        res[method] = pos[np.argmax((pos > 60) & (mean > 400))] - 60
    assert res["filter"] <= res["window"] + 2.0  # within about one update (1.6 m)
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


def test_windows_in_one_filter_do_not_overlap(fake_calibrator):
    bcr = BCR(fake_calibrator, feature="log_var", buffer=1000, update_every=125)
    assert len(bcr.trackers) == 8
    bcr3 = BCR(FakeCalibrator(), feature="log_var", buffer=1000, update_every=300)
    assert len(bcr3.trackers) == 4  # windows 1,200 samples apart
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
