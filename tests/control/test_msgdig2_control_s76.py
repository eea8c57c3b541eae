"""Session 76 (helper, msgdig2): the BCR's, the Simplex's and control's other messages give a
value just past the bound it was checked against with the digits that tell the two apart
(``gpmsa.errors.numbers_text``); ordinary values read as before. Before, a probability just
below plausibility_p read "(p = 1e-06 < 1e-06)", a GD just above GD_max "GD 350 > GD_max 350",
a speed just past the emulator's domain "speed 2 m/s outside the emulator's [0.5, 2]"."""

import copy
import re

import numpy as np
import pytest
from control_doubles import FakeBlockModel, FakeCalibrator, stream
from scipy.special import ndtri
from scipy.stats import chi2

import control
import roadgen
from control import BCR, PAPER_WINDOW, ControlError, Estimate, FeatureSpec, Simplex
from control.sensor_checks import MAX_ACCEL_MPS2
from control.training import block_statistics

JUST_BELOW = 1e-6 * (1 - 1e-7)  # just below plausibility_p's default, 1e-6


def const(gd):
    return lambda s: np.full_like(s, gd)


def feed(bcr, t, p, a, v, chunk=42):
    return [
        bcr.update(t[k : k + chunk], p[k : k + chunk], a[k : k + chunk], v[k : k + chunk])
        for k in range(0, t.size, chunk)
    ]


class _Plausibility(FakeBlockModel):
    """FakeBlockModel whose 10th block's plausibility check gives probability ``p``."""

    def __init__(self, p: float):
        super().__init__()
        self.p, self.checks = p, 0

    def plausibility(self, y, v):
        self.checks += 1
        d2, p = super().plausibility(y, v)
        return (d2, self.p) if self.checks == 10 else (d2, p)


@pytest.mark.parametrize(
    ("p", "says"), [(JUST_BELOW, "(p = 9.999999e-07 < 1e-06)"), (3e-9, "(p = 3e-09 < 1e-06)")]
)
def test_a_block_just_below_plausibility_p_reads_below_it(p, says):
    ests = feed(BCR(_Plausibility(p)), *stream(const(400), 1.5, 10, seed=1))
    flagged = [e.reason for e in ests if e.status == "implausible"]
    assert len(flagged) == 1 and "squared Mahalanobis distance" in flagged[0]
    assert f"distance 5 {says}; the block before it is undone" in flagged[0]


class _Scores(FakeBlockModel):
    """FakeBlockModel whose level scores are 0 but for the given ones (call number -> score)."""

    def __init__(self, scores: dict[int, float]):
        super().__init__()
        self.scores, self.calls_ = scores, 0

    def level_score(self, y, v, direction):
        self.calls_ += 1
        return self.scores.get(self.calls_, 0.0)


def test_a_quiet_phase_and_its_hold_just_past_their_limits_read_past_them():
    # the 10th score reads p just below plausibility_p (the quiet check flags it, a hold
    # begins), the 11th (another phase) p just below release_p (0.05): the hold goes on
    quiet, held = ndtri(JUST_BELOW), ndtri(0.05 * (1 - 1e-7))
    ests = feed(BCR(_Scores({10: quiet, 11: held})), *stream(const(400), 1.5, 10, seed=1))
    flagged = [e.reason for e in ests if e.status == "implausible"]
    assert "level score -4.75 sd (p = 9.999999e-07 < 1e-06); a sensor gain" in flagged[0]
    assert "(level score -1.64 sd, p = 0.049999995 < release_p 0.05)" in flagged[1]


def test_an_ordinary_quiet_phase_and_hold_read_as_before():
    ests = feed(BCR(_Scores({10: -6.0, 11: -2.5})), *stream(const(400), 1.5, 10, seed=1))
    flagged = [e.reason for e in ests if e.status == "implausible"]
    assert "level score -6 sd (p = 9.9e-10 < 1e-06); a sensor gain or noise" in flagged[0]
    assert "(level score -2.5 sd, p = 0.0062 < release_p 0.05)" in flagged[1]


@pytest.mark.parametrize(
    ("z", "says"),
    [
        (ndtri(1e-6) * (1 - 1e-9), "level score -4.75342430407 sd, a sensor at rest reads below "
                                   "-4.75342430882)"),
        (1.5, "level score 1.5 sd, a sensor at rest reads below -4.75)"),
    ],
)  # fmt: skip
def test_frozen_odometry_just_past_its_limit_reads_past_it(z, says):
    class Level(FakeBlockModel):
        def level_score(self, y, v, direction):
            return z

    t, p, a, v = stream(const(400), 1.5, 10, seed=1)
    ts = t[-1] + np.arange(1, 4 * 125 + 1) / 120  # then standing, the accelerometer as before
    n = ts.size
    bcr = BCR(Level())
    feed(bcr, t, p, a, v)
    ests = feed(bcr, ts, np.full(n, p[-1]), a[:n], np.zeros(n))
    reasons = [e.reason for e in ests if "the speeds read standing" in e.reason]
    assert reasons and all(says in why for why in reasons), [e.reason for e in ests]


@pytest.mark.parametrize(
    ("speed", "says"), [(2 * (1 + 1e-8), "2.00000002"), (2.345, "2.35"), (0.25, "0.25")]
)
def test_a_speed_just_past_the_domain_reads_past_it(speed, says):
    ests = feed(BCR(FakeBlockModel()), *stream(const(400), speed, 3, seed=1))
    assert f"speed {says} m/s outside the emulator's [0.5, 2]" in ests[-1].reason
    bcr = BCR(FakeCalibrator(), method="window", feature=PAPER_WINDOW)
    ests = feed(bcr, *stream(const(400), speed, 10, seed=1), chunk=125)
    assert f"window speed {says} m/s outside the emulator's range [0.5, 2] m/s" in ests[-1].reason


@pytest.mark.parametrize(
    ("p", "says"), [(JUST_BELOW, "(p = 9.999999e-07 < 1e-06)"), (3e-9, "(p = 3e-09 < 1e-06)")]
)
def test_a_window_just_below_plausibility_p_reads_below_it(p, says):
    cal = FakeCalibrator()
    cal.emulator.predict = lambda v, gd: (np.zeros((gd.size, 1)), np.ones((gd.size, 1)))
    bcr = BCR(cal, method="window", feature=PAPER_WINDOW)
    why, got = bcr._window_implausible(1.5, float(np.sqrt(chi2.isf(p, 1))))
    assert got == pytest.approx(p, rel=1e-9) and got < 1e-6
    assert why.endswith(f"predictive sds from the nearest {says}")


@pytest.mark.parametrize("past", [True, False])
def test_an_estimate_just_past_max_age_reads_past_it(past):
    bcr = BCR(FakeBlockModel(), max_age_s=3.0, max_silence_s=10.0)
    last = feed(bcr, *stream(const(400), 1.5, 3, seed=1))[-1]
    assert last.ok
    now = last.data_time + (3.0 if past else 3.5)
    while past and not now - last.data_time > 3.0:
        now = np.nextafter(now, np.inf)
    est = bcr.update([], [], [], [], now=now)
    assert est.status == "stale"
    age = now - last.data_time
    says = f"{age:.17g} s old (max_age_s = 3)" if past else "3.50 s old (max_age_s = 3)"
    assert est.reason == f"newest information is {says}"


@pytest.mark.parametrize("past", [True, False])
def test_a_silence_just_past_max_silence_s_reads_past_it(past):
    bcr = BCR(FakeBlockModel(), max_silence_s=0.5)
    t, p, a, v = stream(const(400), 1.5, 3, seed=1)
    feed(bcr, t, p, a, v)
    now = t[-1] + (0.5 if past else 0.8)
    while past and not now - t[-1] > 0.5:
        now = np.nextafter(now, np.inf)
    est = bcr.update([], [], [], [], now=now)
    assert est.status == "sensor_fault"
    says = f"{now - t[-1]:.17g}" if past else "0.80"
    assert est.reason == f"no samples for {says} s (max_silence_s = 0.5)"


@pytest.mark.parametrize(("gd", "says"), [(350 * (1 + 1e-9), "350.00000035"), (351.25, "351.2")])
def test_a_gd_just_past_gd_max_reads_past_it(gd, says):
    est = Estimate(1.0, 1.0, "ok", gd_mean=gd, gd_sd=10.0, interval=(gd - 5, gd + 5))
    command = Simplex().command(est)
    assert command.mode == "safety" and command.reason == f"GD {says} > GD_max 350"


@pytest.mark.parametrize(("peak", "says"), [(MAX_ACCEL_MPS2 * (1 + 1e-9), "100000.0001"),
                                            (2.5e5, "2.5e+05")])  # fmt: skip
def test_training_accelerations_just_past_their_limit_read_past_it(peak, says):
    spec = FeatureSpec()
    accel = np.random.default_rng(1).normal(0.0, 1.0, (1, 2 * 8 * spec.block_samples))
    accel[0, 7] = peak
    with pytest.raises(ControlError, match=re.escape(f"accel reaches {says} m/s^2, beyond any ")):
        block_statistics(accel, spec)


@pytest.mark.parametrize(("v_max", "says"), [(2 * (1 + 1e-9), "2.000000002"), (5.0, "5")])
def test_a_v_max_just_past_the_top_speed_reads_past_it(emulator_a, v_max, says):
    track = roadgen.track([(20, 300)], seed=1)
    top = f"^Simplex v_max = {says} m/s exceeds the vehicle's top speed 2 m/s$"
    with pytest.raises(ControlError, match=top):
        control.run_closed_loop(track, emulator_a, simplex=Simplex(v_max=v_max))


@pytest.mark.parametrize(("edge", "says"), [(60 + 2e-9, "60.000000002"), (61.5, "61.5")])
def test_a_band_edge_just_past_nyquist_reads_past_it(edge, says):
    above = f"^bands_hz reach {says} Hz, above the Nyquist frequency 60 Hz$"
    with pytest.raises(ControlError, match=above):
        FeatureSpec(bands_hz=(1.0, 10.0, edge))


@pytest.mark.parametrize(("v", "says"), [(2 + 2e-11, "2.00000000002"), (2.5, "2.5")])
def test_the_observation_models_speed_check_reads_past_its_range(likelihood_a, v, says):
    model = copy.copy(likelihood_a)
    model.speed_range = (1.99, 2.0)  # a narrow domain: its 1e-9 tolerance is 1e-11 m/s
    with pytest.raises(ControlError, match=rf"^speed {says} m/s outside .* \[1\.99, 2\]$"):
        model._at(v)
