"""Mutation testing of control/bcr.py (session 93, every 4th site from the first): exact cases
on the doubles of control_doubles.py (each test's numbers are worked by hand in its comments)."""

import copy

import numpy as np
import pytest
from control_doubles import FakeBlockModel, FakeCalibrator, stream

import control
from control import BCR


def test_the_window_checks_read_the_newest_125_samples_not_126():
    # update_every 10: 10 + CHECK_CONTEXT (32) = 42 < CHECK_LEAST = 125, so each update's
    # signal checks read the newest 125 samples. Pile A: 5 samples at +0.5 (indices 4, 20, 40,
    # 60, 80), pile B: 5 at -0.5 (120, 122, ..., 128), the rest white noise. The 13th update
    # (samples 0-129) reads 5-129: pile A holds 4 samples there, within max_same = 4, and pile
    # B 5: one pile over the limit, no clipping. Reading 126 samples would take in index 4 and
    # see two piles of 5: "clipped signal". The 12th update (0-119) holds pile A alone.
    bcr = BCR(FakeCalibrator(), method="window", feature=control.PAPER_WINDOW, update_every=10)
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 130 / 120, seed=5)
    a = a.copy()
    a[[4, 20, 40, 60, 80]] = 0.5
    a[[120, 122, 124, 126, 128]] = -0.5
    statuses = [
        bcr.update(*(x[k : k + 10] for x in (t, p, a, v))).status for k in range(0, 130, 10)
    ]
    assert statuses == ["filling"] * 13
    # one more sample of pile A inside the newest 125 is a fault, as a check of the setup
    bcr = BCR(FakeCalibrator(), method="window", feature=control.PAPER_WINDOW, update_every=10)
    a[5] = 0.5
    est = [bcr.update(*(x[k : k + 10] for x in (t, p, a, v))) for k in range(0, 130, 10)][-1]
    assert est.status == "sensor_fault" and est.reason.startswith("clipped signal: 5 samples")


def test_a_new_bcr_and_a_restored_one_have_built_the_taper_tables():
    # `BCR._warm_up`: the log band power's DPSS tapers are built at construction and when a
    # copy or an unpickled BCR is restored, not inside the control loop's first block
    from control import feature

    model = FakeBlockModel()  # (its own statistics build the tapers once a process)
    feature._tapers.cache_clear()
    bcr = BCR(model)
    assert feature._tapers.cache_info().currsize == 1
    feature._tapers.cache_clear()
    copy.copy(bcr)
    assert feature._tapers.cache_info().currsize == 1


def test_from_emulator_with_settings_refuses_an_emulator_that_records_no_feature():
    # BCR(model) takes a model whose emulator records no feature as it is; from_emulator
    # builds the model from the emulator and needs the record, with settings given too
    emu = copy.deepcopy(control.shipped_emulator("A", "window"))
    settings = control.BCRSettings(method="window", feature=control.PAPER_WINDOW)
    assert control.BCR.from_emulator(emu, settings).settings == settings
    del emu.metadata["feature"]
    with pytest.raises(control.EmulatorMismatchError, match="has no 'feature'"):
        control.BCR.from_emulator(emu, settings)


def test_the_hold_warning_steps_down_where_the_products_floor_lands_one_over():
    # max_age_s one ulp below 23 / 120: 0.19166666666666665 * 120 rounds to 23.0, and
    # 23 / 120 = 0.19166666666666668 is above it, so the largest update_every held within
    # max_age_s is 22 samples (22 / 120 = 0.18333 s), not 23
    max_age = 0.19166666666666665
    assert 23 / 120.0 > max_age >= 22 / 120.0
    with pytest.warns(control.ControlWarning) as caught:
        control.BCRSettings(
            method="window", feature=control.PAPER_WINDOW, update_every=125, max_age_s=max_age
        )
    assert "lower update_every to at most 22 samples or raise" in str(caught[0].message)


def test_the_silence_before_any_sample_counts_from_the_first_calls_clock():
    # no sample ever: the silence runs from the first call's now= (0 s), not the newest one
    bcr = BCR(FakeBlockModel())  # max_silence_s = 0.5
    empty = np.zeros(0)
    assert bcr.update(empty, empty, empty, empty, now=0.0).status == "filling"
    assert bcr.update(empty, empty, empty, empty, now=0.25).status == "filling"
    est = bcr.update(empty, empty, empty, empty, now=10.0)
    assert est.status == "sensor_fault"
    assert est.reason == "no samples for 10.00 s (max_silence_s = 0.5)"


class _PlausibleAtTheLimit(FakeBlockModel):
    """Every block's plausibility exactly 1e-6, the default plausibility_p."""

    def plausibility(self, y, v):
        return super().plausibility(y, v)[0], 1e-6


def test_a_block_whose_probability_equals_plausibility_p_is_plausible():
    # "implausible" is a probability below plausibility_p (BCRSettings): equal to it is not
    bcr = BCR(_PlausibleAtTheLimit(), update_every=125)
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 125 / 120, seed=3)
    est = bcr.update(t, p, a, v)
    assert est.status == "ok"
    bcr = BCR(_PlausibleAtTheLimit(), update_every=125, plausibility_p=2e-6)
    assert bcr.update(t, p, a, v).status == "implausible"


def test_a_window_whose_variance_underflows_has_no_feature():
    # samples of ~1e-170 m/s^2 pass the signal checks, but their squares (~1e-340) underflow:
    # variance 0, log variance -inf: a sensor fault, not an estimate
    bcr = BCR(FakeCalibrator(), method="window", feature=control.PAPER_WINDOW)
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 1000 / 120, seed=3)
    est = bcr.update(t, p, a * 1e-170, v)
    assert est.status == "sensor_fault"
    assert est.reason == "window feature undefined (zero variance?)"


def test_a_window_speed_beyond_the_emulators_range_carries_the_last_estimate():
    # 1,000 samples at 1.5 m/s (an estimate), then 1,000 at 3 m/s: the windows' mean speed
    # passes 2 m/s; the newest ok estimate is carried, its time and position moved to the
    # newest sample's (16.7 s and 12.5 + 25 = 37.5 m: not the time as a position)
    bcr = BCR(FakeCalibrator(), method="window", feature=control.PAPER_WINDOW, max_age_s=30.0)
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 1000 / 120, seed=3)
    assert bcr.update(t, p, a, v).status == "ok"
    t2, p2, a2, v2 = stream(
        lambda s: np.full_like(s, 400.0), 3.0, 1000 / 120, seed=4, t0=t[-1], s0=p[-1]
    )
    est = bcr.update(t2, p2, a2, v2)
    assert est.status == "ok" and (est.time, est.position) == (t2[-1], p2[-1])
    assert est.position == pytest.approx(37.5) and est.time == pytest.approx(1000 / 60)
    assert est.reason.startswith(
        "no new information: window speed 3 m/s outside the emulator's range [0.5, 2] m/s"
    )


def test_the_tempered_filter_weighs_each_update_by_its_new_samples():
    # the first full window is new (power 1,000 / 1,000); each later update brings 125 new
    # samples of the 1,000: power 0.125
    bcr = BCR(FakeCalibrator(), method="tempered", feature=control.PAPER_WINDOW)
    (tracker,) = bcr.trackers
    powers = []
    update = tracker.update

    def spy(grid, loglik, power=1.0):
        powers.append(power)
        return update(grid, loglik, power=power)

    tracker.update = spy
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 1250 / 120, seed=3)
    for k in range(0, 1250, 125):
        bcr.update(t[k : k + 125], p[k : k + 125], a[k : k + 125], v[k : k + 125])
    assert powers == [1.0, 0.125, 0.125]


def _loud_blocks(speed, n=500):
    """``n`` samples loud as driving at 1.5 m/s over GD 400, their odometry reading ``speed``."""
    t, _, a, _ = stream(lambda s: np.full_like(s, 400.0), 1.5, n / 120, seed=3)
    return t, speed * t, a, np.full(n, speed)


def test_a_block_at_exactly_the_standing_speed_is_not_standing():
    # standing: every |speed| below STANDING_MPS = 0.05 m/s; at 0.05 m/s the blocks read as a
    # speed outside the emulator's range, never as frozen odometry (as 0.049 m/s reads)
    for speed, first in ((0.05, "speed 0.05 m/s outside"), (0.049, "the speeds read standing")):
        bcr = BCR(FakeBlockModel(), update_every=125)
        t, p, a, v = _loud_blocks(speed)
        reasons = [bcr.update(t[k : k + 125], p[k : k + 125], a[k : k + 125], v[k : k + 125])
                   for k in range(0, 500, 125)]  # fmt: skip
        assert reasons[0].status == "out_of_domain" and reasons[0].reason.startswith(first)
        assert (reasons[-1].status == "sensor_fault") == (speed < 0.05)


def test_a_block_whose_slowest_speed_is_below_half_its_fastest_carries_no_information():
    # speeds 0.6 -> 1.5 m/s (mean 1.05, in the range): 0.6 < 0.5 * 1.5 = 0.75
    bcr = BCR(FakeBlockModel(), update_every=125)
    t, _, a, _ = stream(lambda s: np.full_like(s, 400.0), 1.5, 125 / 120, seed=3)
    v = np.linspace(0.6, 1.5, 125)
    est = bcr.update(t, np.cumsum(v) / 120, a, v)
    assert est.status == "out_of_domain"
    assert est.reason == "speed changed within the block (0.6-1.5 m/s)"


def test_recent_change_m_may_be_zero():
    assert control.BCRSettings(recent_change_m=0.0).recent_change_m == 0.0
    with pytest.raises(control.ControlError, match="recent_change_m"):
        control.BCRSettings(recent_change_m=-1.0)


def test_a_length_mismatch_names_the_array_against_ts_length():
    bcr = BCR(FakeBlockModel())
    with pytest.raises(control.ControlError, match=r"^position must have t's length 3, got 2$"):
        bcr.update(np.arange(3.0), np.arange(2.0), np.zeros(3), np.ones(3))


def test_a_break_waiting_for_the_coming_update_is_named_before_the_silence():
    # 50 samples, a dropped one among them (a 2-sample step at sample 20), fewer than an
    # update (125): the break waits for the coming update; now= 10 s after the newest sample
    bcr = BCR(FakeBlockModel(), update_every=125)
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 51 / 120, seed=3)
    keep = np.arange(51) != 20
    t, p, a, v = t[keep], p[keep], a[keep], v[keep]
    est = bcr.update(t, p, a, v, now=t[-1] + 10.0)
    assert est.status == "sensor_fault"
    waiting = bcr._pending_fault()
    assert waiting and est.reason == f"{waiting}; no samples for 10.00 s (max_silence_s = 0.5)"


class _LoudBy(FakeBlockModel):
    """Every block implausible (probability 0), its band powers reading as ``gain`` times."""

    def __init__(self, gain):
        super().__init__()
        self.gain = gain

    def plausibility(self, y, v):
        return 1e3, 0.0

    def band_gain(self, y, v, bands):
        return self.gain


def test_the_gain_clause_starts_at_unit_hint_gain_either_way():
    # UNIT_HINT_GAIN = 3: a gain of 3 or more, or of 1/3 or less, is named (the lower edge is
    # test_bcr_rest_s92's); between them, no clause
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 125 / 120, seed=3)
    for gain, clause in ((3.0, True), (2.99, False), (0.34, False), (0.33, True)):
        est = BCR(_LoudBy(gain), update_every=125).update(t, p, a, v)
        assert est.status == "implausible"
        assert ("its band powers read as" in est.reason) == clause, gain
    assert est.reason.endswith(
        "its band powers read as the smoothest ground's acceleration times 0.33"
    )


def test_a_window_estimates_latency_lies_within_the_calls_own_duration():
    # latency_s: the time spent computing the estimate, inside update (an ordering, not a
    # timing: 0 <= latency <= the call's duration on the same clock)
    import time

    bcr = BCR(FakeCalibrator(), method="window", feature=control.PAPER_WINDOW)
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 1000 / 120, seed=3)
    tic = time.perf_counter()
    est = bcr.update(t, p, a, v)
    toc = time.perf_counter()
    assert est.status == "ok" and 0.0 <= est.latency_s <= toc - tic
