"""The shortcuts of BCR.update's hot path (session 72) give what the long way gives, bit for bit:
the stream checks' fast path (`_unbroken`), the sorted stretches the dead and lattice checks
share (`_sorted_runs`), and the change-point filter's kept survival S(d) (`_survival_now`)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import gammaincc

from control.changepoint import ChangePointFilter, ChangePointSettings
from control.sensor_checks import (
    MAX_SPEED_MPS,
    NO_BREAKS,
    _dead_stretch,
    _lattice_stretch,
    _resolution,
    _sorted_runs,
    _unbroken,
    _window_index,
    stream_breaks,
)

RATE = 120.0


def _stream(rng, n):
    t = 100.0 + np.arange(n) / RATE
    return t, np.cumsum(np.full(n, 0.0125)), rng.normal(size=n), np.full(n, 1.5)


def test_unbroken_is_true_for_a_clean_stream_and_false_for_each_break():
    rng = np.random.default_rng(0)
    t, pos, acc, spd = _stream(rng, 42)
    dt = 1.0 / RATE
    assert _unbroken(t, pos, acc, spd, t[0] - dt, dt)
    assert _unbroken(t, pos, acc, spd, np.nan, dt)  # no sample before: no first step
    assert not _unbroken(t[:0], pos[:0], acc[:0], spd[:0], np.nan, dt)
    for which, k, value in [
        (0, 5, np.nan), (1, 5, np.inf), (2, 5, -np.inf), (3, 5, np.nan),
        (3, 5, MAX_SPEED_MPS * 1.01), (3, 5, -MAX_SPEED_MPS * 1.01),
        (0, 5, t[4]), (0, 5, t[5] + 2 * dt),  # a repeated stamp; a gap
        (2, slice(5, 7), 1e308),  # finite, but the sum overflows: stream_breaks decides
    ]:  # fmt: skip
        arrays = [a.copy() for a in (t, pos, acc, spd)]
        arrays[which][k] = value
        assert not _unbroken(*arrays, t[0] - dt, dt), (which, value)
    assert not _unbroken(t, pos, acc, spd, t[0] - 2 * dt, dt)  # a gap before the first
    assert not _unbroken(t, pos, acc, spd, t[0], dt)  # the first stamp repeated


@pytest.mark.filterwarnings("ignore:invalid value:RuntimeWarning")  # (the long way's, on inf)
def test_stream_breaks_fast_path_gives_the_long_way_answer():
    rng = np.random.default_rng(1)
    dt = 1.0 / RATE
    taken = 0
    for _ in range(400):
        n = int(rng.integers(1, 40))
        t, pos, acc, spd = _stream(rng, n)
        t = t + rng.normal(0, dt * rng.choice([0.0, 0.2, 0.6]), n)
        for a in (t, pos, acc, spd):
            if rng.random() < 0.1:
                a[rng.integers(n)] = rng.choice([np.nan, np.inf, 60.0, -60.0])
        t_prev = rng.choice([np.nan, t[0] - dt, t[0] - 2 * dt])
        drop, restart, found = stream_breaks(t, pos, acc, spd, t_prev, RATE)
        fast = _unbroken(t, pos, acc, spd, t_prev, dt)
        assert fast == (not drop.any() and not restart.any() and found == NO_BREAKS)
        taken += fast
    assert 50 < taken < 350


def test_sorted_runs_are_each_stretch_sorted_and_shared_checks_agree():
    rng = np.random.default_rng(2)
    a = rng.normal(size=125)
    a[40:50] = 0.3  # a dead stretch
    runs = _sorted_runs(a, 6)
    assert runs.shape == (6, 120)
    for i in (0, 57, 119):
        np.testing.assert_array_equal(runs[:, i], np.sort(a[i : i + 6]))
    assert _sorted_runs(a[:5], 6) is None
    sd = float(np.std(a))
    for free_fall in (None, 0.3, -9.81):
        assert _dead_stretch(a, 1e-3, free_fall, sd, runs[-1] - runs[0]) == _dead_stretch(
            a, 1e-3, free_fall, sd
        )  # fmt: skip
    q = np.round(rng.normal(size=125) / 0.05) * 0.05 + rng.normal(0, 1e-9, 125)
    r = _resolution(q)
    assert _lattice_stretch(q, 6, None, r, _sorted_runs(q, 6)) == _lattice_stretch(q, 6, None, r)
    assert np.array_equal(_window_index(125, 6)[:, 3], np.arange(3, 9))


@pytest.mark.parametrize("shape", [2.0, 1.0])
def test_kept_survival_is_the_survival_of_the_distances(shape):
    s = ChangePointSettings(segment_shape=shape, max_runs=6)  # merges from the 6th step on
    f = ChangePointFilter(np.geomspace(100.0, 700.0, 33), s)
    g = ChangePointFilter(np.geomspace(100.0, 700.0, 33), s)  # recomputes every S(d)
    rng = np.random.default_rng(3)
    for k in range(14):
        ds = float(rng.uniform(0.3, 3.0))
        loglik = rng.normal(0, 2, 33)
        if k == 9:
            f.relocate(5.0)
            g.relocate(5.0)
        elif k == 11:  # a restored state: its arrays are new, nothing kept applies
            f.restore(f.state())
            g.restore(g.state())
        else:
            f.update(loglik, ds)
            g.update(loglik, ds)
        g._survival = None
        theta = s.mean_segment_m / s.segment_shape
        expected = gammaincc(shape, f._dist / theta)
        if shape != 1.0:
            np.testing.assert_array_equal(f._survival_now(), expected)
            kept = k not in (0, 11)  # (the first block runs no hazard; a restore keeps none)
            assert (f._survival is not None and f._survival[0] is f._dist) == kept
        np.testing.assert_array_equal(f._mass, g._mass)
        np.testing.assert_array_equal(f._dist, g._dist)
    assert f._dist.size == 6
