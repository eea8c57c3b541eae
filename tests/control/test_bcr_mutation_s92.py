"""Mutation testing of control/bcr.py (session 92): behaviour that no test pinned, found by
mutants of every 4th site (from the 3rd) that survived the cheapest covering BCR tests. Each test
names what it pins; all run on the doubles of control_doubles.py."""

from dataclasses import replace

import numpy as np
import pytest
from control_doubles import FakeBlockModel, FakeCalibrator, stream

from control import BCR, PAPER_WINDOW, BCRSettings
from control.errors import ControlWarning
from control.tracker import GDTracker, TrackerSettings


def _drive(gd: float, seconds: float, seed: int = 1):
    """A drive at 1.5 m/s over a constant GD (t, position, accel, speed)."""
    return stream(lambda s: np.full_like(s, gd), 1.5, seconds, seed=seed)


def _feed(bcr: BCR, samples, chunk: int = 42) -> list:
    t, p, a, v = samples
    return [
        bcr.update(t[k : k + chunk], p[k : k + chunk], a[k : k + chunk], v[k : k + chunk])
        for k in range(0, t.size, chunk)
    ]


def test_the_quiet_check_remembers_16_blocks_a_phase_by_default():
    assert BCRSettings().quiet_blocks == 16
    bcr = BCR(FakeBlockModel())
    assert [phase.levels.maxlen for phase in bcr._phases] == [16, 16, 16]


def test_a_numpy_integer_update_every_is_stored_as_a_python_int():
    s = BCRSettings(update_every=np.int64(42))
    assert type(s.update_every) is int and s.update_every == 42


def test_reset_forgets_the_gd_state_of_every_phase():
    # after a reset the BCR estimates as a new one does: its filters hold no GD state of the
    # drive before (GD 500), so a drive over GD 300 gives a new BCR's numbers exactly
    used, new = BCR(FakeBlockModel()), BCR(FakeBlockModel())
    _feed(used, _drive(500.0, 5.0, seed=2))
    used.reset()
    assert not any(phase.filter.has_data for phase in used._phases)
    a, b = _feed(used, _drive(300.0, 4.0)), _feed(new, _drive(300.0, 4.0))
    assert a[-1].ok and b[-1].ok
    assert [e.gd_mean for e in a] == [e.gd_mean for e in b]


def test_the_hold_warning_offers_update_every_where_the_largest_held_equals_the_least():
    # 1 sample at 120 Hz is the largest update_every held within max_age_s = 1/120 s, and the
    # window methods allow 1: the remedy is offered at equality
    with pytest.warns(ControlWarning) as caught:
        BCRSettings(method="window", feature=PAPER_WINDOW, update_every=2, max_age_s=1 / 120)
    text = str(caught[0].message)
    assert "lower update_every to at most 1 samples or raise max_age_s" in text
    assert "(update_every is at least" not in text


def test_float64_stamps_given_as_a_list_are_not_refused_for_their_resolution():
    # the resolution check reads float32/float16 stamps only: float64 ones at 1e13 s (2 ms
    # apart there) are the caller's, not the type's, and are taken
    t, p, a, v = _drive(300.0, 0.5)
    est = BCR(FakeBlockModel()).update(list(t + 1e13), p, a, v)
    assert est.status == "filling"


def test_a_clock_step_back_onto_a_sample_without_position_moves_the_newest_time_back_too():
    # the drive's newest sample at 10 s, then the clock restarts at 2 s with a sample whose
    # position is missing: the newest kept sample's time moves back by the step (8 s + one
    # period), so the estimate (its data time moved back as well) is 0.1 s old, not stale
    t, p, a, v = _drive(300.0, 5.0)
    bcr = BCR(FakeBlockModel())
    assert _feed(bcr, (t - t[-1] + 10.0, p, a, v))[-1].ok
    est = bcr.update([2.0], [np.nan], [0.1], [1.5])
    back = 8.0 + 1 / 120
    assert est.status == "ok"
    assert est.time == pytest.approx(9.9 - back, abs=1e-12)
    assert est.data_time == pytest.approx(9.9 - back, abs=1e-12)


def test_the_window_method_forgets_each_window_before_the_next():
    # method "window": each estimate is one window's likelihood on the prior (the tracker is
    # reset before every update), never the product of the windows so far
    bcr = BCR(FakeCalibrator(), method="window", feature=PAPER_WINDOW)
    t, p, a, v = _drive(300.0, 12.0)
    ests = [e for e in _feed(bcr, (t, p, a, v), chunk=125) if e.ok]
    assert len(ests) >= 3
    for est in ests:
        tracker = GDTracker(bcr.gd_range, replace(TrackerSettings(), mean_segment_m=0.0))
        grid, loglik = FakeCalibrator().log_likelihood_grid([[est.speed]], [[est.feature[0]]])
        tracker.update(np.ravel(grid), np.ravel(loglik))
        post = tracker.posterior("GD")
        assert est.gd_mean == pytest.approx(post.mean("GD"), rel=1e-12)
        assert est.gd_sd == pytest.approx(post.sd("GD"), rel=1e-12)


class _GainModel(FakeBlockModel):
    """FakeBlockModel whose blocks' band powers read as a set gain (``band_gain``)."""

    def __init__(self, gain: float):
        super().__init__()
        self.gain = gain

    def band_gain(self, y, v, bands):
        return self.gain


def _implausible_reason(gain: float) -> str:
    t, p, a, v = _drive(300.0, 3.0)
    ests = _feed(BCR(_GainModel(gain)), (t, p, 1e3 * a, v))
    reasons = [e.reason for e in ests if e.status == "implausible"]
    assert reasons
    return reasons[0]


def test_the_mm_unit_slip_is_named_within_a_factor_2_of_1000_only():
    assert "mm/s^2" in _implausible_reason(1999.0)
    assert "mm/s^2" in _implausible_reason(500.5)
    beyond = _implausible_reason(2001.0)
    assert "mm/s^2" not in beyond and "times 2e+03" in beyond


def test_an_empty_call_names_the_silence_alone_not_the_breaks_of_waiting_samples():
    # a NaN accel among 10 samples of the coming update waits for that update's estimate; an
    # empty call 1 s after the newest sample reports the silence only
    t, p, a, v = _drive(300.0, 5.0)
    bcr = BCR(FakeBlockModel())
    n = 42 * 14
    _feed(bcr, (t[:n], p[:n], a[:n], v[:n]))
    part = slice(n, n + 10)
    acc = a[part].copy()
    acc[3] = np.nan
    bcr.update(t[part], p[part], acc, v[part])
    est = bcr.update([], [], [], [], now=float(t[n + 9]) + 1.0)
    assert (est.status, est.reason) == (
        "sensor_fault",
        "no samples for 1.00 s (max_silence_s = 0.5)",
    )


def test_a_clock_step_back_moves_the_window_methods_data_time_back():
    # method "window": the newest window's data time (20 s) moves back with the clock's step
    # (18 s + one period) as the estimate's does, so the fault that names the step rests on it
    bcr = BCR(FakeCalibrator(), method="window", feature=PAPER_WINDOW)
    t, p, a, v = _drive(300.0, 12.5)  # 12 updates of 125 samples
    last = _feed(bcr, (t - t[-1] + 20.0, p, a, v), chunk=125)[-1]
    assert last.ok and last.data_time == 20.0
    t2 = 2.0 + np.arange(125) / 120.0
    est = bcr.update(t2, p[-1] + 1.5 * (t2 - 2.0 + 1 / 120), a[:125], v[:125])
    assert est.status == "sensor_fault" and "the sample clock stepped back 18.01 s" in est.reason
    assert est.data_time == pytest.approx(20.0 - (18.0 + 1 / 120), abs=1e-12)
