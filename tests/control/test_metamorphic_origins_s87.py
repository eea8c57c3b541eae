"""Metamorphic checks of the BCR (session 87): inputs transformed so that the estimates must not
change. The time origin (stamps from 0 s, since the epoch, negative) changes nothing, bit for
bit, faults included; the odometry's origin (1e6 m, 1e9 m) changes statuses and reasons
nothing and the numbers within the float64 resolution of the positions; a copy or pickle of a
BCR with its SimplexRun mid-stream goes on as the original. Before: the estimates returned
before the first update carried the time and position 0 of the BCR's placeholder, not the
newest sample's (at epoch stamps, 1.7e9 s off)."""

import copy
import pickle

import numpy as np
import pytest
from control_doubles import FakeBlockModel, FakeCalibrator, stream

from control import BCR, PAPER_WINDOW, Simplex

EVERY = 42


def _samples():
    """A 30 s drive from GD 300 to 500 with a gap, a repeated stamp and a clock step back."""
    t, p, a, v = stream(lambda s: np.where(s < 15.0, 300.0, 500.0), 1.5, 30.0, seed=2)
    t = t.copy()
    t[1500:] += 2 / 120  # two dropped samples
    t[2000] = t[1999]  # a repeated stamp
    t[2800:] -= 30.0  # the sample clock steps back 30 s
    return t, p, a, v


def _new(method: str) -> BCR:
    if method == "changepoint":
        return BCR(FakeBlockModel())
    return BCR(FakeCalibrator(), method=method, feature=PAPER_WINDOW)


def _feed(bcr, samples, chunk=EVERY, now=True):
    t, p, a, v = samples
    out = []
    for k in range(0, t.size, chunk):
        part = slice(k, k + chunk)
        clock = float(t[part][-1]) if now else None
        out.append(bcr.update(t[part], p[part], a[part], v[part], now=clock))
    return out


def _said(e) -> str:
    """Everything an estimate says but its time and position, NaN equal to NaN."""
    return repr((e.status, e.reason, e.gd_mean, e.gd_sd, e.interval, e.speed, e.prob_change,
                 e.plausibility_p, e.domain_edge,
                 None if e.feature is None else np.ravel(e.feature).tolist()))  # fmt: skip


@pytest.mark.parametrize("method", ["changepoint", "window"])
@pytest.mark.parametrize("chunk", [1, EVERY])
def test_the_estimates_before_the_first_update_carry_the_newest_samples_time(method, chunk):
    """Before: "k of the first update's n samples" read time 0.0 and position 0.0 (the
    placeholder's), 1.7e9 s and 1e6 m from the samples fed."""
    t, p, a, v = _samples()
    t0, s0 = 1.7e9, 1e6
    bcr = _new(method)
    every = bcr.settings.samples_per_update
    for k in range(0, every - 1, chunk):
        part = slice(k, min(k + chunk, every - 1))
        est = bcr.update(t[part] + t0, p[part] + s0, a[part], v[part])
        assert est.status == "filling" and "of the first update's" in est.reason
        assert est.time == t[part][-1] + t0 and est.position == p[part][-1] + s0


def test_a_resumed_bcr_stamps_its_first_samples_on_their_own_clock():
    t, p, a, v = _samples()
    bcr = BCR(FakeBlockModel())
    _feed(bcr, [x[:600] for x in (t, p, a, v)])
    bcr.resume(0.0)
    est = bcr.update(t[600:610] + 100.0, p[600:610], a[600:610], v[600:610])
    assert est.reason == "resumed (0 m moved while down); 10 of the first update's 42 samples"
    assert (est.time, est.position) == (t[609] + 100.0, p[609])


@pytest.mark.parametrize("method", ["changepoint", "window", "filter"])
@pytest.mark.parametrize("t0", [1.7e9, -1e3])
def test_the_time_origin_changes_nothing_but_the_times(method, t0):
    """Epoch stamps in float64 (spaced 2.4e-7 s at 1.7e9 s) and negative ones: the same
    statuses, reasons (gap, repeated stamp, clock step) and numbers, bit for bit; the times
    shifted within the stamps' spacing."""
    t, p, a, v = _samples()
    ref = _feed(_new(method), (t, p, a, v))
    got = _feed(_new(method), (t + t0, p, a, v))
    assert [_said(e) for e in got] == [_said(e) for e in ref]
    reasons = " ".join(e.reason for e in ref)
    assert "a gap of" in reasons and "stepped back 30 s" in reasons
    assert "repeated or backwards" in reasons
    spacing = np.spacing(abs(t0) + t[-1])
    assert max(abs(g.time - t0 - r.time) for g, r in zip(got, ref, strict=True)) <= spacing
    assert np.allclose([g.data_time - t0 for g in got], [r.data_time for r in ref],
                       rtol=0, atol=spacing, equal_nan=True)  # fmt: skip


@pytest.mark.parametrize("s0", [1e6, 1e9])
def test_the_odometry_origin_moves_the_numbers_within_the_positions_resolution(s0):
    """A long-lived robot's odometry: statuses and reasons alike; the change-point filter's
    distances carry the positions' float64 spacing (1.2e-7 m at 1e9 m), which moved GD by
    at most 6.5e-7 and its sd by 4e-8 relative on this drive."""
    t, p, a, v = _samples()
    ref = _feed(BCR(FakeBlockModel()), (t, p, a, v))
    got = _feed(BCR(FakeBlockModel()), (t, p + s0, a, v))
    assert [(e.status, e.reason) for e in got] == [(e.status, e.reason) for e in ref]
    ok = [(g, r) for g, r in zip(got, ref, strict=True) if r.ok]
    assert len(ok) > 30
    for name in ("gd_mean", "gd_sd", "prob_change"):
        pairs = np.array([(getattr(g, name), getattr(r, name)) for g, r in ok])
        np.testing.assert_allclose(pairs[:, 0], pairs[:, 1], rtol=1e-15 * s0, atol=0, err_msg=name)
    assert [g.position - s0 for g in got] == pytest.approx([r.position for r in ref], abs=1e-6)


def test_with_now_a_call_of_several_updates_stamps_them_with_its_clock_and_nothing_else():
    """By design (docs/robot.md, "Chunks"): with ``now=``, the updates of one call are stamped
    at the call's clock; their statuses, numbers and data times are those of 42 a call."""
    t, p, a, v = _samples()
    ref, got = [], []
    for chunk, out in ((EVERY, ref), (5 * EVERY + 11, got)):
        bcr = BCR(FakeBlockModel())
        made = bcr._estimate
        bcr._estimate = lambda made=made, out=out: out.append(made()) or out[-1]
        _feed(bcr, (t, p, a, v), chunk)
    assert [_said(e) for e in got] == [_said(e) for e in ref]
    assert np.array_equal([e.data_time for e in got], [e.data_time for e in ref], equal_nan=True)
    assert [e.time for e in got] != [e.time for e in ref]


@pytest.mark.parametrize("how", ["copy", "deepcopy", "pickle"])
def test_a_bcr_and_its_simplex_run_copied_mid_stream_go_on_as_the_originals(how):
    """Cut at every 17th update, faults, a latch and the release dwell among them."""
    twin = {"copy": copy.copy, "deepcopy": copy.deepcopy,
            "pickle": lambda x: pickle.loads(pickle.dumps(x))}[how]  # fmt: skip
    t, p, a, v = _samples()
    a = a.copy()
    a[2400:2410] = np.nan
    samples = (t, p, a, v)
    simplex = Simplex(release_m=2.0, after_fault="resume")

    def drive(bcr, run, lo, hi):
        return [(e.status, _said(e), repr(run.command(e)))
                for e in _feed(bcr, [x[lo:hi] for x in samples])]  # fmt: skip

    n = t.size // EVERY * EVERY
    ref = drive(BCR(FakeBlockModel()), simplex.start(), 0, n)
    assert {"ok", "sensor_fault"} <= {status for status, *_ in ref}
    for cut in range(0, n, 17 * EVERY):
        bcr, run = BCR(FakeBlockModel()), simplex.start()
        head = drive(bcr, run, 0, cut)
        assert head + drive(twin(bcr), twin(run), cut, n) == ref, cut
