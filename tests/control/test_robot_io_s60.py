"""The BCR's time base in a robot user's loop: a sample clock that steps back (session 60)."""

import functools

import numpy as np
import pytest
from control_doubles import FakeBlockModel, stream

from control import BCR

EVERY = 42
STEP_S = 30.0  # an NTP correction, a bag replayed from its start, a driver restart
AT = 1260  # the first sample on the stepped clock (an update boundary: 30 x 42)


def _feed(bcr, t, p, a, v, chunk=EVERY, now=None):
    """Estimates of ``bcr`` fed in chunks; ``now``: the caller's clock per sample (None: none)."""
    out = []
    for k in range(0, t.size, chunk):
        part = slice(k, k + chunk)
        clock = None if now is None else float(now[min(k + chunk, t.size) - 1])
        out.append(bcr.update(t[part], p[part], a[part], v[part], now=clock))
    return out


def _stepped(t):
    return np.where(np.arange(t.size) >= AT, t - STEP_S, t)


def test_a_sample_clock_that_steps_back_while_now_does_not_is_named_as_such():
    """Before: every later update read "no samples for 30.00 s" while samples arrived."""
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 20, seed=1)
    ests = _feed(BCR(FakeBlockModel()), _stepped(t), p, a, v, now=t)
    assert all(e.ok for e in ests[3 : AT // EVERY])
    after = ests[AT // EVERY :]
    assert all(e.status == "sensor_fault" for e in after)  # the clocks disagree: no estimate
    assert "1 repeated or backwards time stamp(s)" in after[0].reason
    for e in after:
        assert "the sample clock stepped back 30 s" in e.reason, e.reason
        assert "30.00 s behind the caller's clock (now=" in e.reason, e.reason
        assert "no samples for" not in e.reason, e.reason


def test_a_caller_clock_that_steps_with_the_samples_resumes():
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 20, seed=1)
    stepped = _stepped(t)
    ests = _feed(BCR(FakeBlockModel()), stepped, p, a, v, now=stepped)
    after = ests[AT // EVERY :]
    assert after[0].status == "sensor_fault" and "stepped back 30 s" in after[0].reason
    assert all(e.ok and not e.reason for e in after[8:])


@pytest.mark.parametrize("chunk", [1, 42])
def test_after_a_clock_step_back_a_carried_estimate_still_turns_stale(chunk):
    """Before: the newest information kept its time on the old clock, 30 s ahead of the new
    samples, and an estimate carried while standing stayed "ok" for 35 s, not 5."""
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 10.5, seed=1)
    n = 120 * 10  # then 10 s standing (no new information), on a clock 30 s back
    t2 = t[-1] - STEP_S + np.arange(1, n + 1) / 120
    rng = np.random.default_rng(2)
    still = (t2, np.full(n, p[-1]), 0.01 * rng.standard_normal(n), np.zeros(n))
    bcr = BCR(FakeBlockModel())
    assert _feed(bcr, t, p, a, v, chunk)[-1].ok
    ests = _feed(bcr, *still, chunk)
    since = np.array([e.time for e in ests]) - (t[-1] - STEP_S)  # s standing, new clock
    carried = [e for e, s in zip(ests, since, strict=True) if 1.0 < s < 3.5]
    assert carried and all(e.ok and "no new information" in e.reason for e in carried)
    late = [e for e, s in zip(ests, since, strict=True) if s > 5.5]
    assert late and all(e.status == "stale" and "s old" in e.reason for e in late)


def test_one_stamp_far_back_costs_a_block_in_any_chunking():
    """A single wild stamp (not a clock step: the next one is back on time) costs a block or
    two and the same final estimate in any chunking. Among good stamps of its chunk it moves
    nothing: no clock step is named and every estimate's data time stays within seconds of
    its time (the review found them 1.7e9 s apart after a 0.0 stamp). Alone at a chunk's end
    it reads as a step back (the cautious side: what is held reads older)."""
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 30, seed=1)
    wild = t.copy()
    wild[2000] -= 1000.0
    finals = {}
    for chunk in (1, 7, 42, 125):
        out = _feed(BCR(FakeBlockModel()), wild, p, a, v, chunk, now=t)
        faults = [e for e in out if e.status == "sensor_fault"]
        assert out[-1].ok and len({e.time for e in faults}) <= 2, (chunk, faults)
        named = any("stepped back 1000 s" in e.reason for e in faults)
        assert named == (chunk == 1), (chunk, faults)
        if chunk > 1:
            lags = [e.time - e.data_time for e in out if np.isfinite(e.data_time)]
            assert max(abs(lag) for lag in lags) < 5.0, chunk
        finals[chunk] = out[-1].gd_mean
    assert len(set(finals.values())) == 1, finals  # the same estimate, however chunked


# --- docs/robot.md, "Your own loop": the measured figures ------------------------------------


def _drive(parts, noise):
    """(t, position, measured acceleration, speed) of a 1.5 m/s drive over ``parts`` ((length
    m, GD), ...), simulated once a (parts, noise) and shared read-only (several tests drive the
    same road)."""
    return _simulated(tuple(map(tuple, parts)), noise)


@functools.cache
def _simulated(parts, noise):
    import roadgen
    import vehicle

    trace = vehicle.simulate(vehicle.Jackal(), roadgen.track(list(parts), seed=1), 1.5,
                             noise_std=noise, seed=1)  # fmt: skip
    out = (trace.t, trace.position, trace.accel_front_measured, trace.speed)
    for x in out:
        x.setflags(write=False)
    return out


def _loop(bcr, t, p, a, v):
    """(estimates, SimplexRun) of ``bcr`` fed one update at a time with now=, as a robot."""
    import control

    run = control.Simplex().start()
    out = []
    for k in range(0, t.size - EVERY + 1, EVERY):
        part = slice(k, k + EVERY)
        out.append(bcr.update(t[part], p[part], a[part], v[part], now=float(t[k + EVERY - 1])))
        run.command(out[-1])
    return out, run


def test_gravity_left_in_reaches_the_checks_of_emulator_a_only(new_bcr):
    for case, noise in (("B", 1.0), ("A", 0.0)):
        t, p, a, v = _drive([(40.0, 300.0), (40.0, 500.0)], noise)
        free, _ = _loop(new_bcr(case), t, p, a, v)
        assert len(free) == 151 and sum(e.ok for e in free) == 149
        raw, run = _loop(new_bcr(case), t, p, a + 9.81, v)
        if case == "B":
            assert [e.status for e in raw] == [e.status for e in free] and not run.latched
            gd = np.array([e.gd_mean for e in raw if e.ok])
            np.testing.assert_allclose(gd, [e.gd_mean for e in free if e.ok], atol=1e-9)
            continue
        assert sum(e.status == "sensor_fault" for e in raw) == 94
        assert run.latched and run.latched_by.position == pytest.approx(2.4, abs=0.05)
        for offset in (-0.45, 0.45):  # gravity subtracted, not exactly
            near, run = _loop(new_bcr(case), t, p, a + offset, v)
            assert [e.status for e in near] == [e.status for e in free] and not run.latched


def test_a_bcr_restored_after_downtime_continues_its_stream_unless_reset(new_bcr):
    import pickle

    t, p, a, v = _drive([(80.0, 300.0)], 1.0)
    half = t.size // 2 // EVERY * EVERY
    bcr = new_bcr("B")
    _loop(bcr, t[:half], p[:half], a[:half], v[:half])
    saved = pickle.dumps(bcr)
    rest = (t[half:] + 600.0, p[half:], a[half:], v[half:])  # 10 min later
    restored = pickle.loads(saved)
    empty = np.empty(0)
    silent = restored.update(empty, empty, empty, empty, now=float(rest[0][0]) - 1 / 120)
    assert silent.status == "sensor_fault" and "no samples for 600.00 s" in silent.reason
    kept, run = _loop(pickle.loads(saved), *rest)
    assert kept[0].status == "sensor_fault" and "a gap of 600 s" in kept[0].reason
    assert run.latched and [e.ok for e in kept].index(True) == 5
    fresh = pickle.loads(saved)
    fresh.reset()
    new, run = _loop(fresh, *rest)
    assert not run.latched and [e.ok for e in new].index(True) == 2
    assert (round(kept[5].gd_sd), round(new[2].gd_sd)) == (49, 85)


def test_a_drive_whose_clock_steps_back_half_way_resumes_with_now_on_that_clock(new_bcr):
    t, p, a, v = _drive([(80.0, 300.0)], 1.0)
    half = t.size // 2 // EVERY * EVERY
    stepped = np.where(np.arange(t.size) >= half, t - STEP_S, t)
    out, _ = _loop(new_bcr("B"), stepped, p, a, v)
    after = [e.status for e in out[half // EVERY :]]
    assert after[:5] == ["sensor_fault"] + ["filling"] * 4 and set(after[5:]) == {"ok"}


def test_a_restored_bcr_resumes_with_its_gd_state_kept_and_moved(new_bcr):
    """Session 62: ``resume(moved_m)`` starts a new stream as ``reset`` does (no latch, the
    first ok estimate at the third update) but keeps the GD state (less each phase's newest
    block, as a gap undoes it), so the first estimates are tighter than ``reset``'s (sd 35
    against 85); a long move forgets most of it, and
    ``math.inf`` is ``reset``."""
    import math
    import pickle

    import control

    t, p, a, v = _drive([(80.0, 300.0)], 1.0)
    half = t.size // 2 // EVERY * EVERY
    bcr = new_bcr("B")
    _loop(bcr, t[:half], p[:half], a[:half], v[:half])
    saved = pickle.dumps(bcr)
    rest = (t[half:] + 600.0, p[half:], a[half:], v[half:])
    sd = {}
    for moved in (0.0, 5.0, 1e4, math.inf):
        resumed = pickle.loads(saved)
        resumed.resume(moved_m=moved)
        assert resumed.last.status == "filling"
        out, run = _loop(resumed, *rest)
        assert not run.latched and [e.ok for e in out].index(True) == 2
        sd[moved] = out[2].gd_sd
        assert abs(out[2].gd_mean - 300.0) < 3 * out[2].gd_sd
    fresh = pickle.loads(saved)
    fresh.reset()
    reset_out, _ = _loop(fresh, *rest)
    assert sd[math.inf] == reset_out[2].gd_sd
    assert sd[0.0] < 0.7 * sd[math.inf] and sd[0.0] <= sd[5.0] < sd[1e4] <= sd[math.inf] * 1.01
    for bad in (-1.0, float("nan"), "5", None):
        with pytest.raises(control.ControlError, match="moved_m must be a real number >= 0"):
            pickle.loads(saved).resume(moved_m=bad)
    t2, p2, a2, v2 = _drive([(40.0, 500.0)], 1.0)  # resumed, wrongly, on rougher ground
    wrong = pickle.loads(saved)
    wrong.resume(moved_m=0.0)
    out, _ = _loop(wrong, t2 + rest[0][0], p2, a2, v2)
    above = [e.position for e in out if e.ok and e.gd_mean > 400.0]
    assert above and above[0] < 5.0  # as a change while driving (measured 3.9 m; reset 1.8 m)


def test_the_window_filters_resume_with_their_tracker_state():
    """``resume`` on method "filter": the tracker's state kept (first sd 47 against 91 after
    ``reset``), forgotten over a long move (as ``reset``)."""
    import pickle

    import control

    t, p, a, v = _drive([(80.0, 300.0)], 1.0)
    half = t.size // 2 // EVERY * EVERY
    bcr = control.BCR.from_emulator(control.shipped_emulator("B", kind="window"), method="filter")
    _loop(bcr, t[:half], p[:half], a[:half], v[:half])
    saved = pickle.dumps(bcr)
    rest = (t[half:] + 600.0, p[half:], a[half:], v[half:])
    first = {}
    for how in (0.0, 1e4, "reset"):
        r = pickle.loads(saved)
        r.reset() if how == "reset" else r.resume(moved_m=how)
        out, run = _loop(r, *rest)
        assert not run.latched
        first[how] = next(e for e in out if e.ok)
    assert first[0.0].gd_sd < 0.6 * first["reset"].gd_sd
    assert first[1e4].gd_sd == pytest.approx(first["reset"].gd_sd, rel=1e-9)


def test_resume_undoes_each_phases_newest_block_as_a_gap_does(new_bcr):
    """The downtime is a gap: each phase's newest block (which may hold the start of what
    stopped the robot) is undone, then the move is propagated over that block's distance too."""
    import copy

    t, p, a, v = _drive([(40.0, 300.0)], 1.0)
    bcr = new_bcr("B")
    _loop(bcr, t, p, a, v)
    expected = []
    for phase in bcr._phases:
        state, _, ds_before = phase.undo
        twin = copy.deepcopy(phase.filter)
        twin.restore(state)
        twin.relocate(2.0 + ds_before)
        expected.append(twin.state())
    bcr.resume(moved_m=2.0)
    for phase, (mass, dist, has_data) in zip(bcr._phases, expected, strict=True):
        got_mass, got_dist, got_has = phase.filter.state()
        np.testing.assert_array_equal(got_mass, mass)
        np.testing.assert_array_equal(got_dist, dist)
        assert got_has == has_data and phase.undo is None
