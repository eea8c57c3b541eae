"""Mutation testing of control/bcr.py (session 93, every 4th site from the second: 1, 5, ...,
873): exact cases on the doubles of control_doubles.py (each test's numbers are worked by hand
in its comments)."""

import math

import numpy as np
import pytest
from control_doubles import FakeBlockModel, FakeCalibrator, stream
from scipy.special import ndtr
from test_bcr_quarter_s93 import _LoudBy

import control
from control import BCR
from control.bcr import GD_MIN_HI, check_gd_unit


def _gd400(n, seed=3):
    """``n`` samples at 1.5 m/s over GD 400 (`stream`)."""
    return stream(lambda s: np.full_like(s, 400.0), 1.5, n / 120, seed=seed)


def _feed(bcr, t, p, a, v, every=125):
    """Feed the samples ``every`` at a time; the estimates."""
    return [
        bcr.update(t[k : k + every], p[k : k + every], a[k : k + every], v[k : k + every])
        for k in range(0, t.size, every)
    ]


def test_reset_and_resume_forget_the_quiet_checks_level_scores():
    # 8 blocks at 0.6x the amplitude (0.36x the power: GD 400 reads as 144, below the domain's
    # 200) fill the one phase's level scores (about -17 summed) and the quiet check flags the
    # later ones. After reset (or resume), a block over GD 400 at full amplitude is "ok", as
    # for a new BCR: its one score alone. Kept, the 8 old scores would sum with it to about
    # -17 / 3 = -5.7 sd, p ~ 6e-9 < 1e-6: "implausible". (resume(0) keeps the GD state: its
    # estimate is "ok" too, its mean not a new BCR's)
    t, p, a, v = _gd400(1000)
    fresh = BCR(FakeBlockModel(), update_every=125).update(t[:125], p[:125], a[:125], v[:125])
    assert fresh.status == "ok"
    for restart in (BCR.reset, lambda bcr: bcr.resume(math.inf), lambda bcr: bcr.resume(0.0)):
        bcr = BCR(FakeBlockModel(), update_every=125)
        ests = _feed(bcr, t, p, 0.6 * a, v)
        assert ests[-1].status == "implausible" and "read quieter" in ests[-1].reason
        restart(bcr)
        assert [len(phase.levels) for phase in bcr._phases] == [0]
        est = bcr.update(t[:125], p[:125], a[:125], v[:125])
        assert est.status == "ok"
    assert est.gd_mean != fresh.gd_mean  # (the last: resume(0))
    bcr.reset()
    assert bcr.update(t[:125], p[:125], a[:125], v[:125]).gd_mean == fresh.gd_mean


def test_a_reset_after_a_resume_drops_the_resumed_note():
    # resume notes "resumed (2 m moved while down); " in the first update's filling reason;
    # a reset after it starts a plain stream again
    t, p, a, v = _gd400(50)
    bcr = BCR(FakeBlockModel(), update_every=125)
    bcr.resume(2.0)
    assert bcr.update(t, p, a, v).reason == (
        "resumed (2 m moved while down); 50 of the first update's 125 samples"
    )
    bcr.reset()
    assert bcr.update(t, p, a, v).reason == "50 of the first update's 125 samples"


def test_a_new_window_buffer_starts_empty():
    # update_every 333: three updates bring 999 samples, one short of the 1,000-sample window
    t, p, a, v = _gd400(999)
    bcr = BCR(FakeCalibrator(), method="window", feature=control.PAPER_WINDOW, update_every=333)
    ests = _feed(bcr, t, p, a, v, every=333)
    assert [(e.status, e.reason) for e in ests] == [
        ("filling", f"buffer holds {n} of 1000 samples") for n in (333, 666, 999)
    ]


def test_a_gd_domain_reaching_gd_min_hi_is_in_the_right_unit():
    # "wholly below GD_MIN_HI" (1): a domain whose top is 1 exactly passes, one below it not
    assert GD_MIN_HI == 1.0
    check_gd_unit((0.1, 1.0))
    with pytest.raises(control.EmulatorMismatchError, match=r"domain \[0.1, 0.999\] lies below 1"):
        check_gd_unit((0.1, 0.999))


def test_interval_level_zero_is_refused():
    with pytest.raises(control.ControlError, match=r"interval_level must lie in \(0, 1\), got 0.0"):
        control.BCRSettings(interval_level=0.0)


class _Scored(FakeBlockModel):
    """Every block plausible (p = 1), its level scores read from ``scores`` in turn."""

    def __init__(self, scores):
        super().__init__()
        self.scores = list(scores)

    def plausibility(self, y, v):
        return 0.0, 1.0

    def level_score(self, y, v, direction):
        return self.scores.pop(0)


def test_a_quiet_probability_equal_to_plausibility_p_is_not_flagged():
    # one block of level score -5 (sd 1 without a scatter's dof): z = -5 exactly, p = ndtr(-5);
    # "quieter" is a probability below plausibility_p: equal is not, one ulp above is
    t, p, a, v = _gd400(125)
    limit = float(ndtr(-5.0))
    assert (
        BCR(_Scored([-5.0]), update_every=125, plausibility_p=limit).update(t, p, a, v).status
        == "ok"
    )
    above = np.nextafter(limit, 1.0)
    est = BCR(_Scored([-5.0]), update_every=125, plausibility_p=above).update(t, p, a, v)
    assert est.status == "implausible"
    assert est.reason.startswith("the last 1 block(s) read quieter than any GD in [200, 600]")


def test_the_quiet_scan_names_the_fewest_blocks_of_a_tie():
    # level scores, oldest first: 6, -6, 0, 0, -6. At the 5th block all five read
    # -6 / sqrt(5) = -2.68 sd (p = 0.0037, no flag); the scan over the newest k: k = 1 reads
    # -6, k = 2 -6 / sqrt(2), k = 3 -6 / sqrt(3), k = 4 -12 / sqrt(4) = -6 again: the tie
    # keeps the first found, the newest block alone
    t, p, a, v = _gd400(625)
    bcr = BCR(_Scored([6.0, -6.0, 0.0, 0.0, -6.0]), update_every=125)
    est = _feed(bcr, t, p, a, v)[-1]
    assert est.status == "implausible"
    assert est.reason.startswith("the last 1 block(s) read quieter")
    assert "level score -6 sd" in est.reason


def test_a_gain_exactly_half_a_unit_slip_names_no_slip():
    # the slip clause needs 0.5 < gain / factor < 2: gain 50 is half of cm/s^2's 100 (the gain
    # clause alone), 50.5 just inside
    t, p, a, v = _gd400(125)
    est = BCR(_LoudBy(50.0), update_every=125).update(t, p, a, v)
    assert est.reason.endswith(
        "its band powers read as the roughest ground's acceleration times 50"
    )
    est = BCR(_LoudBy(50.5), update_every=125).update(t, p, a, v)
    assert est.reason.endswith(
        "times 50: if every block reads so, acceleration in cm/s^2? accel must be m/s^2 (x 0.01)"
    )


def test_a_gain_clause_needs_a_finite_positive_gain():
    # band_gain giving 0, a negative number or infinity names no gain (3 and more does)
    t, p, a, v = _gd400(125)
    for gain in (0.0, -5.0, np.inf, np.nan):
        est = BCR(_LoudBy(gain), update_every=125).update(t, p, a, v)
        assert est.status == "implausible" and "band powers read as" not in est.reason, gain


def test_the_quiet_scan_divides_by_the_scores_sd():
    # a scatter of 4 degrees of freedom: the scores' sd is sqrt(4 / 2) = sqrt(2). Scores 6,
    # then -8: both blocks read -2 / (sqrt(2) sqrt(2)) = -1 sd (p = 0.16); the newest alone
    # -8 / sqrt(2) = -5.66 sd (p = 7.7e-9 < 1e-6)
    from types import SimpleNamespace

    model = _Scored([6.0, -8.0])
    model.scatter = SimpleNamespace(dof=4.0)
    t, p, a, v = _gd400(250)
    est = _feed(BCR(model, update_every=125), t, p, a, v)[-1]
    assert est.status == "implausible"
    assert est.reason.startswith("the last 1 block(s) read quieter")
    assert "level score -5.66 sd (p = 7.7e-09 < 1e-06)" in est.reason


def test_a_changepoint_estimates_latency_lies_within_the_calls_own_duration():
    # latency_s: the time spent computing the estimate, inside update (an ordering, not a
    # timing: 0 <= latency <= the call's duration on the same clock)
    import time

    t, p, a, v = _gd400(125)
    bcr = BCR(FakeBlockModel(), update_every=125)
    tic = time.perf_counter()
    est = bcr.update(t, p, a, v)
    toc = time.perf_counter()
    assert est.status == "ok" and 0.0 <= est.latency_s <= toc - tic


def test_after_resume_the_phases_join_the_pooled_estimate_with_their_first_block():
    # update_every 42: 3 phases. 504 samples give every phase data; resume(0) keeps their GD
    # states but forgets their data times. 126 more samples: the first block (of the newest
    # 125) goes to phase 2, whose filter alone is the estimate; 42 more: phase 0 too, weighed
    # 3 (newest) to phase 2's 2; phase 1, with no block since, is left out
    from control.changepoint import mixture_posterior

    t, p, a, v = _gd400(672)
    bcr = BCR(FakeBlockModel(), update_every=42)
    ests = _feed(bcr, t[:504], p[:504], a[:504], v[:504], every=42)
    assert ests[-1].status == "ok"
    bcr.resume(0.0)
    ests = _feed(bcr, t[504:], p[504:], a[504:], v[504:], every=42)
    assert [e.status for e in ests] == ["filling", "filling", "ok", "ok"]
    filters = [phase.filter for phase in bcr._phases]
    assert [np.isfinite(phase.data_time) for phase in bcr._phases] == [True, False, True]
    # (the third estimate: phase 2's filter as it was then; phase 2 has had no block since)
    assert ests[2].gd_mean == filters[2].posterior("GD").mean("GD")
    assert ests[3].gd_mean == mixture_posterior([filters[0], filters[2]], [3.0, 2.0]).mean("GD")


def test_a_window_at_the_emulators_lowest_speed_is_in_its_range():
    # 1,000 samples at 0.5 m/s exactly: the emulator's unit speed (0.5 - 0.5) / 1.5 = 0
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 0.5, 1000 / 120, seed=3)
    est = BCR(FakeCalibrator(), method="window", feature=control.PAPER_WINDOW).update(t, p, a, v)
    assert (est.status, est.reason) == ("ok", "")


def test_the_windows_predictive_check_reads_65_gds():
    # an emulator predicting y far off everywhere but at GD 206.25, where its variance is
    # infinite: the check's GD grid, linspace(200, 600, 65), steps 6.25 and holds 206.25
    # exactly (z = 0, p = 1: "ok"); a 66-point grid would miss it (p = 0: "implausible")
    calibrator = FakeCalibrator()

    def predict(v, gd):
        var = np.where(gd == 206.25, np.inf, 1.0)
        return np.full((gd.size, 1), 1e6), var[:, None]

    calibrator.emulator.predict = predict
    t, p, a, v = _gd400(1000)
    est = BCR(calibrator, method="window", feature=control.PAPER_WINDOW).update(t, p, a, v)
    assert (est.status, est.reason) == ("ok", "")


def test_update_every_may_be_exactly_an_eighth_of_the_block():
    # MAX_PHASES = 8: a 128-sample block allows update_every 16 (8 phases), not 15
    feature = control.FeatureSpec(block_samples=128)
    assert control.BCRSettings(feature=feature, update_every=16).phases == 8
    with pytest.raises(control.ControlError, match=r"= \[16, 128\], got 15$"):
        control.BCRSettings(feature=feature, update_every=15)


def test_a_short_forward_step_is_no_clock_step_back():
    # max_silence_s 1 ms, below the 8.3 ms sample interval: every sample step counts as
    # "big". Samples 60 on moved 5 ms earlier: one forward step of 3.3 ms (a repeated stamp:
    # the block is skipped), none back; its 5 ms short of the sample interval must not read
    # as the sample clock stepping back
    t, p, a, v = _gd400(250)
    t = t.copy()
    t[60:] -= 0.005
    bcr = BCR(FakeBlockModel(), update_every=125, max_silence_s=0.001)
    est = bcr.update(t, p, a, v)
    assert (est.status, est.reason) == (
        "sensor_fault",
        "1 repeated or backwards time stamp(s); block skipped",
    )


def test_a_window_restarted_by_a_fault_starts_empty():
    # samples 900-999 stuck at 0: the window's 8th update (samples 0-999) is a stuck sensor and
    # restarts the buffer; the next 125 samples fill it from nothing
    t, p, a, v = _gd400(1125)
    a = a.copy()
    a[900:1000] = 0.0
    bcr = BCR(FakeCalibrator(), method="window", feature=control.PAPER_WINDOW)
    ests = _feed(bcr, t, p, a, v)
    assert ests[7].status == "sensor_fault" and ests[7].reason.endswith("; buffer restarted")
    assert (ests[8].status, ests[8].reason) == ("filling", "buffer holds 125 of 1000 samples")


@pytest.mark.parametrize("method", ["filter", "tempered"])
def test_reset_forgets_the_window_trackers_gd_state(method):
    # after reset the same 1,000 samples give a new BCR's first estimate, number for number
    # (the trackers' GD state kept, the second window would narrow the first's posterior)
    t, p, a, v = _gd400(1000)
    fresh = BCR(FakeCalibrator(), method=method, feature=control.PAPER_WINDOW).update(t, p, a, v)
    bcr = BCR(FakeCalibrator(), method=method, feature=control.PAPER_WINDOW)
    assert bcr.update(t, p, a, v).status == fresh.status == "ok"
    bcr.reset()
    est = bcr.update(t, p, a, v)
    assert (est.gd_mean, est.gd_sd, est.interval) == (fresh.gd_mean, fresh.gd_sd, fresh.interval)
