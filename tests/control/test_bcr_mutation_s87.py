"""Mutation testing of control/bcr.py (session 87): behaviour that no test pinned, found by
mutants of the BCR's update, its fault, clock and age checks, resume and reset that survived the
BCR's tests. Each test names what it pins; all run on the doubles of control_doubles.py."""

import numpy as np
from control_doubles import SIGMA, FakeBlockModel, FakeCalibrator, bcr_of, log_f, stream

from control import BCR, PAPER_WINDOW, SensorLimits
from control.feature import FeatureSpec
from control.sensor_checks import signal_fault
from gpmsa.errors import GPMSAError

EVERY = 42  # the change-point method's default update interval on a 125-sample block


def _flat(seconds: float, seed: int = 1, t_end: float | None = None):
    """A drive at 1.5 m/s over GD 300 (t, position, accel, speed); ``t_end``: its last stamp."""
    t, p, a, v = stream(lambda s: np.full_like(s, 300.0), 1.5, seconds, seed=seed)
    if t_end is not None:
        t = t - t[-1] + t_end
    return t, p, a, v


def _feed(bcr: BCR, samples, chunk: int = EVERY, **kw) -> list:
    t, p, a, v = samples
    return [
        bcr.update(t[k : k + chunk], p[k : k + chunk], a[k : k + chunk], v[k : k + chunk], **kw)
        for k in range(0, t.size, chunk)
    ]


def test_resume_leaves_the_placeholder_of_a_new_bcr_at_time_and_position_zero():
    bcr = BCR(FakeBlockModel())
    _feed(bcr, _flat(3.0))
    bcr.resume(2.0)
    last = bcr.last
    assert (last.status, last.time, last.position) == ("filling", 0.0, 0.0)
    assert last.reason == "resumed (2 m moved while down); no samples yet"


def test_the_odometry_check_reads_the_blocks_own_samples_only():
    # positions that follow the speeds exactly pass a check with no slack: a block's positions
    # are its own samples' (one sample more would move 1.25 cm more than its speeds say)
    limits = SensorLimits(odometry_tolerance=1e-6, odometry_slack_m=0.0)
    bcr = BCR(FakeBlockModel(), sensor=limits)
    ests = _feed(bcr, _flat(5.0))
    assert {e.status for e in ests} == {"filling", "ok"}
    assert ests[-1].ok


def _stepped_back(first_stamp: float) -> str:
    """The reason of the fault that samples give whose stamps restart at ``first_stamp`` after
    a drive whose last stamp was 10 s."""
    bcr = BCR(FakeBlockModel())
    t, p, a, v = _flat(5.0, t_end=10.0)
    bcr.update(t, p, a, v)
    t2, p2, a2, v2 = _flat(1.0, seed=3)
    est = bcr.update(t2 - t2[0] + first_stamp, p[-1] + p2, a2, v2)
    assert est.status == "sensor_fault"
    return est.reason


def test_a_stamp_back_by_max_silence_s_is_a_backwards_stamp_and_more_restarts_the_clock():
    # the time base restarts where t steps back by more than max_silence_s (0.5 s), by the
    # clock's step: against the place the next sample would have had (10 s + 1 / 120 s)
    exactly = _stepped_back(9.5)
    assert exactly.startswith("1 repeated or backwards time stamp(s); block skipped")
    assert "stepped back" not in exactly
    beyond = _stepped_back(5.0 + 1 / 120)
    assert beyond.startswith("1 repeated or backwards time stamp(s) (the sample clock stepped "
                             "back 5 s); block skipped")  # fmt: skip


def test_steps_of_one_chunk_that_net_exactly_max_silence_s_back_restart_nothing():
    # a stamp 1 s back and a later one 0.515625 s forward, in one chunk at 128 Hz (exact binary
    # steps): they move the clock back by 1 + 1/128 - (0.515625 - 1/128) = 0.5 s, not more
    spec = FeatureSpec(rate_hz=128.0)
    base = BCR(FakeBlockModel(spec), feature=spec)
    n = EVERY * 15  # whole updates: the next chunk is one part
    t = 10.0 - np.arange(n)[::-1] / 128.0
    _, _, a, v = stream(lambda s: np.full_like(s, 300.0), 1.5, n / 128.0, rate_hz=128.0)
    base.update(t, 1.5 * t, a, v)
    reasons = []
    for forward in (0.515625, 0.515625 - 1 / 128):
        bcr = base.__copy__()
        t2 = 9.0 + np.arange(EVERY) / 128.0
        t2[20:] += forward - 1 / 128
        est = bcr.update(t2, 1.5 * t2 + 20.0, a[:EVERY], v[:EVERY])
        assert est.status == "sensor_fault"
        reasons.append(est.reason)
    assert "stepped back" not in reasons[0]
    assert "(the sample clock stepped back 0.5078 s)" in reasons[1]


def test_silence_of_exactly_max_silence_s_is_no_fault_and_longer_is():
    bcr = BCR(FakeBlockModel())
    t, p, a, v = _flat(5.0, t_end=10.0)
    bcr.update(t, p, a, v, now=10.0)
    none = np.empty(0)
    assert bcr.update(none, none, none, none, now=10.5).ok  # 0.5 s: the limit, not past it
    late = bcr.update(none, none, none, none, now=10.5 + 1e-9)
    assert late.status == "sensor_fault"
    assert late.reason == "no samples for 0.500000001 s (max_silence_s = 0.5)"


def test_a_silence_after_a_filling_estimate_names_the_silence_alone():
    # the reason of a fresh sensor fault is named before the silence, not that of any estimate
    bcr = BCR(FakeBlockModel())
    t, p, a, v = _flat(0.5, t_end=10.0)
    assert bcr.update(t, p, a, v, now=10.0).status == "filling"
    none = np.empty(0)
    est = bcr.update(none, none, none, none, now=11.0)
    assert est.status == "sensor_fault"
    assert est.reason == "no samples for 1.00 s (max_silence_s = 0.5)"


def test_a_stop_and_start_mid_window_reads_no_dead_sensor_for_the_window_method():
    # a robot that comes to rest and gets under way again reads an all but constant
    # acceleration: a dead stretch that takes in a slow sample is no fault, with the window full
    bcr = bcr_of("window")
    n, dt = 1500, 1 / 120
    speed = np.ones(n)
    speed[1250:1256] = np.linspace(0.8, 0.0, 6)
    speed[1256:1296] = 0.0
    speed[1296:] = np.minimum(20.0 * dt * np.arange(1, n - 1296 + 1), 1.0)
    t = np.arange(1, n + 1) * dt
    accel = np.random.default_rng(0).normal(0.0, 0.5, n)
    accel[1254:1300] = 1e-6 * np.arange(46)  # the stop: quiet
    assert "dead sensor" in signal_fault(accel[1218:1375], SensorLimits(), steady=False)
    ests = _feed(bcr, (t, np.cumsum(speed) * dt, accel, speed), chunk=125)
    assert [e.status for e in ests] == ["filling"] * 7 + ["ok"] * 5


def test_a_fault_in_the_first_block_undoes_nothing():
    bcr = BCR(FakeBlockModel())
    t, p, a, v = _flat(3.0)
    a = a.copy()
    a[100] = np.nan  # in the first update with a whole block
    ests = _feed(bcr, (t, p, a, v))
    faults = [e.reason for e in ests if e.status == "sensor_fault"]
    assert faults == ["1 sample(s) with non-finite accel; block skipped"]


def test_a_block_whose_power_underflows_in_a_band_is_a_sensor_fault():
    # accelerations of 1e-200 m/s^2 pass the signal checks (no noise floor without the
    # sensor's noise sd) but their band powers underflow to 0: no feature to read
    bcr = BCR(FakeBlockModel())
    t, p, a, v = _flat(2.0)
    ests = _feed(bcr, (t, p, a * 1e-200, v))
    assert ests[-1].status == "sensor_fault"
    assert ests[-1].reason == "a band of the block has no power"


def _frozen_drive(**overrides) -> list:
    """Estimates every 0.25 s (32 samples at 128 Hz: exact stamps) of a drive at 1.5 m/s whose
    odometry freezes (position held, speed 0) after 4 s while the accelerometer drives on."""
    spec = FeatureSpec(rate_hz=128.0)
    bcr = BCR(FakeBlockModel(spec), feature=spec, update_every=32, **overrides)
    _, p, a, v = stream(lambda s: np.full_like(s, 300.0), 1.5, 8.0, rate_hz=128.0, seed=4)
    t = np.arange(1, a.size + 1) / 128.0
    frozen = t > 4.0
    p, v = p.copy(), v.copy()
    p[frozen], v[frozen] = p[frozen][0], 0.0
    return _feed(bcr, (t, p, a, v), chunk=32)


def test_frozen_odometry_is_a_fault_once_it_has_read_standing_for_exactly_the_settle_time():
    # the first standing block starts at 4.03 s (its estimate at 5 s); the block that starts
    # STANDING_SETTLE_S = 2 s after it (at 7 s) is the first fault
    ests = [e for e in _frozen_drive() if e.time >= 5.0]
    assert [e.status for e in ests] == ["out_of_domain"] * 8 + ["sensor_fault"] * 5
    assert ests[0].reason.startswith(
        "the speeds read standing (below 0.05 m/s) but the accelerometer reads as driving at "
        "0.5 m/s or faster (level score "
    )
    assert ests[-1].reason.startswith("frozen odometry: the speeds read standing")


def test_without_the_quiet_signal_check_frozen_odometry_reads_as_standing():
    # quiet_blocks=0 or plausibility_p=0 switch the check off: the estimate is carried
    for overrides in ({"quiet_blocks": 0}, {"plausibility_p": 0.0}):
        ests = [e for e in _frozen_drive(**overrides) if e.time >= 5.0]
        assert {e.status for e in ests} == {"ok"}
        assert all(e.reason.startswith("no new information: speed 0 m/s outside") for e in ests)


def test_a_block_whose_lowest_speed_is_half_its_highest_is_used():
    # speeds alternating 1 and 2 m/s: the lowest is not below MAX_SPEED_CHANGE (0.5) of the
    # highest, so the block carries information (at their mean, 1.5 m/s)
    _, _, a, _ = _flat(4.0)
    v = np.where(np.arange(a.size) % 2, 2.0, 1.0)
    t = np.arange(1, a.size + 1) / 120.0
    p = np.concatenate([[0.0], np.cumsum((v[1:] + v[:-1]) / 2.0 / 120.0)])  # as the trapezoid
    ests = _feed(BCR(FakeBlockModel()), (t, p, a, v))
    assert {e.status for e in ests} == {"filling", "ok"}
    assert all(e.reason == "" for e in ests if e.ok)


def test_one_phases_mass_by_run_is_its_filters():
    bcr = BCR(FakeBlockModel(), update_every=125)  # one phase: no pooling
    _feed(bcr, _flat(5.0), chunk=125)
    edges = [2.0, 5.0]
    assert np.array_equal(bcr.mass_by_run(edges), bcr.filter.mass_by_run(edges))


class _FailingCalibrator(FakeCalibrator):
    def log_likelihood_grid(self, x_obs, y_obs):
        raise GPMSAError("the emulator cannot predict here")


def test_a_calibrators_error_is_a_calibration_failed_estimate_of_the_window_method():
    bcr = BCR(_FailingCalibrator(), method="window", feature=PAPER_WINDOW)
    ests = _feed(bcr, _flat(10.0), chunk=125)
    assert ests[-1].status == "calibration_failed"
    assert ests[-1].reason == "the emulator cannot predict here"


def _predicting_window_bcr() -> BCR:
    """The window method on a calibrator whose emulator predicts the law of control_doubles
    (log f, sd SIGMA): the scalar predictive check runs."""
    calibrator = FakeCalibrator()
    calibrator.emulator.predict = lambda v, gd: (
        log_f(np.asarray(v), np.asarray(gd))[:, None],
        np.full((np.size(gd), 1), SIGMA**2),
    )
    return BCR(calibrator, method="window", feature=PAPER_WINDOW)


def test_a_window_that_some_gd_explains_is_plausible():
    # GD 300 explains it; GD 600 lies log(2) / SIGMA = 11.6 sds away: the check reads the
    # nearest GD's distance, not the farthest
    ests = _feed(_predicting_window_bcr(), _flat(10.0), chunk=125)
    assert ests[-1].ok


def test_a_window_no_gd_explains_is_implausible():
    bcr = _predicting_window_bcr()
    t, p, a, v = _flat(10.0)
    ests = _feed(bcr, (t, p, a * 1e-2, v), chunk=125)  # 1e-4 of the variance: GD 0.03
    assert ests[-1].status == "implausible"
    assert ests[-1].reason.startswith("no GD in [200, 600] explains the window at 1.5 m/s")
    assert ests[-1].plausibility_p < bcr.settings.plausibility_p
